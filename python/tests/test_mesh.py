"""Mesh I/O and simplification: shapes, values against the command-line tool, errors."""

import json
import subprocess

import numpy as np
import pytest

import meshgnn


def test_read_mesh_gives_float32_vertices_and_int64_faces(icosphere_path):
    V, F = meshgnn.read_mesh(icosphere_path)
    assert V.dtype == np.float32 and V.shape == (162, 3)
    assert F.dtype == np.int64 and F.shape == (320, 3)
    # The fixture is icosphere(2) of radius 1.5 centred at (0.25, -0.5, 1).
    radii = np.linalg.norm(V - np.array([0.25, -0.5, 1.0]), axis=1)
    np.testing.assert_allclose(radii, 1.5, rtol=1e-5)


def test_write_then_read_round_trips(tmp_path, icosphere_path):
    V, F = meshgnn.read_mesh(icosphere_path)
    for name in ("out.ply", "out.obj", "out.off"):
        meshgnn.write_mesh(tmp_path / name, V, F)
        V2, F2 = meshgnn.read_mesh(str(tmp_path / name))
        np.testing.assert_array_equal(F2, F)
        np.testing.assert_allclose(V2, V, rtol=1e-6)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out.obj", "out.off", "out.ply"]


def test_points_round_trip(tmp_path):
    X = np.random.default_rng(0).normal(size=(50, 3)).astype(np.float32)
    meshgnn.write_points(tmp_path / "cloud.ply", X)
    np.testing.assert_array_equal(meshgnn.read_points(tmp_path / "cloud.ply"), X)


def test_simplify_matches_the_command_line_tool(tmp_path, creature_path, cli):
    V, F = meshgnn.read_mesh(creature_path)
    V2, F2, vertex_map, info = meshgnn.simplify(
        V, F, faces=4460, return_vertex_map=True, return_info=True
    )
    out = tmp_path / "cli.ply"
    report = subprocess.run(
        [cli("meshsimplify"), "simplify", creature_path, "-o", out, "--faces", "4460", "--json"],
        check=True, capture_output=True, text=True,
    )
    expected = json.loads(report.stdout)
    for key in ("input_faces", "output_faces", "error", "stop_reason"):
        assert info[key] == expected[key], key
    assert info["output_faces"] == len(F2) and info["collapses"] > 0
    V_cli, F_cli = meshgnn.read_mesh(out)
    np.testing.assert_array_equal(F2, F_cli)
    np.testing.assert_array_equal(V2, V_cli)
    assert vertex_map.shape == (len(V),) and vertex_map.max() < len(V2)
    assert len(F2) <= 4461


def test_simplify_keeps_landmarks_like_the_command_line_tool(tmp_path, creature_path, cli):
    V, F = meshgnn.read_mesh(creature_path)
    keep = np.arange(0, len(V), 997)
    V2, F2, vertex_map = meshgnn.simplify(V, F, faces=4460, keep=keep, return_vertex_map=True)
    np.testing.assert_array_equal(V2[vertex_map[keep]], V[keep])
    assert len(np.unique(vertex_map[keep])) == len(keep)
    landmarks = tmp_path / "landmarks.txt"
    landmarks.write_text(", ".join(map(str, keep)))
    out = tmp_path / "cli.ply"
    subprocess.run(
        [cli("meshsimplify"), "simplify", creature_path, "-o", out, "--faces", "4460",
         "--keep", landmarks],
        check=True, capture_output=True,
    )
    V_cli, F_cli = meshgnn.read_mesh(out)
    np.testing.assert_array_equal(F2, F_cli)
    np.testing.assert_array_equal(V2, V_cli)
    V3, F3 = meshgnn.simplify(V, F, faces=4460, keep=keep.tolist())
    np.testing.assert_array_equal(F3, F2)


def test_neural_simplify_matches_the_command_line_tool(tmp_path, creature_path, cli):
    V, F = meshgnn.read_mesh(creature_path)
    V2, F2, vertex_map, info = meshgnn.simplify(
        V, F, ratio=0.05, method="neural", seed=2, fill_holes=30,
        return_vertex_map=True, return_info=True,
    )
    out = tmp_path / "cli.ply"
    report = subprocess.run(
        [cli("meshsimplify"), "simplify", creature_path, "-o", out, "--ratio", "0.05",
         "--method", "neural", "--seed", "2", "--fill-holes", "30", "--json"],
        check=True, capture_output=True, text=True,
    )
    expected = json.loads(report.stdout)
    for key in ("input_faces", "output_faces", "error", "stop_reason", "wa_raw", "wa", "holes"):
        assert info[key] == expected[key], key
    V_cli, F_cli = meshgnn.read_mesh(out)
    np.testing.assert_array_equal(F2, F_cli)
    np.testing.assert_array_equal(V2, V_cli)
    # The neural method selects: each kept input vertex maps to its output vertex, the rest
    # to -1. Hole filling may add a vertex after the kept ones for a hole no triangulation of
    # its corners closes, the centre of a fan of at least three faces.
    # About 5 % of the vertices are kept: vertices cut off from their nearest drawn vertex
    # get seeds of their own, the draw shrinking by as many (2 232 for 2 230 here).
    kept = np.flatnonzero(vertex_map >= 0)
    target = round(0.05 * len(V))
    assert abs(len(kept) - target) <= 0.01 * target and len(kept) <= len(V2)
    assert vertex_map[kept].max() == len(kept) - 1
    assert (vertex_map[vertex_map < 0] == -1).all()
    added = np.arange(len(kept), len(V2))
    assert all((F2 == v).any(axis=1).sum() >= 3 for v in added)
    # By default the kept vertices move to their regions' quadric optima, a small step;
    # keep_positions leaves them at the input vertices, with the same faces.
    V3, F3, map3 = meshgnn.simplify(
        V, F, ratio=0.05, method="neural", seed=2, fill_holes=30, keep_positions=True,
        return_vertex_map=True,
    )
    np.testing.assert_array_equal(map3, vertex_map)
    np.testing.assert_array_equal(V3[vertex_map[kept]], V[kept])
    step = np.linalg.norm(V2[vertex_map[kept]] - V[kept], axis=1)
    diagonal = np.linalg.norm(V.max(axis=0) - V.min(axis=0))
    assert (step > 0).mean() > 0.5 and step.max() < 0.05 * diagonal


def test_neural_simplify_refuses_small_meshes(icosphere_path):
    V, F = meshgnn.read_mesh(icosphere_path)
    with pytest.raises(ValueError) as error:
        meshgnn.simplify(V, F[:80], ratio=0.5, method="neural")
    assert "80 faces" in str(error.value) and "at least 100" in str(error.value)


def test_simplify_accepts_float64_and_int32_and_ratio(icosphere_path):
    V, F = meshgnn.read_mesh(icosphere_path)
    a = meshgnn.simplify(V, F, ratio=0.25)
    b = meshgnn.simplify(V.astype(np.float64), F.astype(np.int32), faces=80)
    assert len(a[1]) == 80
    for x, y in zip(a, b):
        np.testing.assert_array_equal(x, y)
    # A non-contiguous view gives the same result as its copy.
    wide = np.zeros((len(V), 6), dtype=np.float32)
    wide[:, ::2] = V
    np.testing.assert_array_equal(meshgnn.simplify(wide[:, ::2], F, faces=80)[1], a[1])


@pytest.mark.parametrize(
    "change, message",
    [
        (lambda V, F: (V[:, :2], F), "V: expected shape (n, 3), got (162, 2)"),
        (lambda V, F: (V.astype(np.int64), F), "V: expected a float32 or float64 array"),
        (lambda V, F: (V, F.astype(np.float32)), "F: expected an int32 or int64 array"),
        (lambda V, F: (np.where(np.arange(162)[:, None] == 7, np.nan, V), F), "vertex 7"),
        (lambda V, F: (V, np.where(F == 5, 999, F)), "999"),
        (lambda V, F: (V, np.where(F == 5, -1, F)), "vertex index -1"),
        (lambda V, F: (V[:0], F[:0]), "V, F: "),
        (lambda V, F: (V, F[:0]), "no faces"),
    ],
)
def test_simplify_rejects_bad_arrays_with_one_line(icosphere_path, change, message):
    V, F = meshgnn.read_mesh(icosphere_path)
    with pytest.raises(ValueError) as error:
        meshgnn.simplify(*change(V, F), ratio=0.5)
    assert message in str(error.value) and "\n" not in str(error.value)


@pytest.mark.parametrize(
    "kwargs, message",
    [
        ({}, "give exactly one of ratio= and faces="),
        ({"ratio": 0.5, "faces": 10}, "give exactly one"),
        ({"ratio": 1.5}, "ratio=1.5 is outside (0, 1]"),
        ({"ratio": 1e-9}, "keeps 0 of the input's 320 faces"),
        ({"faces": 0}, "faces=0"),
        ({"faces": 321}, "more than the input's 320 faces"),
        ({"ratio": 0.5, "method": "edge"}, 'method="edge"'),
        ({"ratio": 0.5, "max_error": -1.0}, "max_error=-1"),
        ({"ratio": 0.5, "seed": 3}, 'seed= applies to method="neural" only'),
        ({"ratio": 0.5, "fill_holes": 30}, 'fill_holes= applies to method="neural" only'),
        ({"ratio": 0.5, "keep_positions": True}, 'keep_positions= applies to method="neural" only'),
        ({"ratio": 0.5, "method": "neural", "max_error": 1.0}, 'applies to method="qem" only'),
        ({"ratio": 0.5, "method": "neural", "keep": [1]}, 'keep= applies to method="qem" only'),
        ({"ratio": 0.5, "keep": [3, -1]}, "keep: entry 1 is -1"),
        ({"ratio": 0.5, "keep": [1000]}, "vertex 1000 to keep"),
        ({"ratio": 0.5, "keep": "abc"}, "keep: expected"),
        ({"ratio": 0.5, "method": "neural", "fill_holes": 5000}, "fill_holes=5000"),
        ({"ratio": 0.5, "method": "neural", "weights": "missing.safetensors"}, "missing.safetensors"),
    ],
)
def test_simplify_rejects_bad_requests(icosphere_path, kwargs, message):
    V, F = meshgnn.read_mesh(icosphere_path)
    with pytest.raises(ValueError, match=None) as error:
        meshgnn.simplify(V, F, **kwargs)
    assert message in str(error.value)


def test_file_errors_name_the_file(tmp_path):
    with pytest.raises(OSError) as error:
        meshgnn.read_mesh(tmp_path / "missing.obj")
    assert "missing.obj" in str(error.value)
    broken = tmp_path / "broken.ply"
    broken.write_bytes(b"ply\nformat binary_little_endian 1.0\nelement vertex 99\n")
    with pytest.raises(ValueError) as error:
        meshgnn.read_mesh(broken)
    assert "broken.ply" in str(error.value) and "\n" not in str(error.value)
    with pytest.raises(ValueError) as error:
        meshgnn.write_mesh(tmp_path / "out.xyz3", np.zeros((3, 3), np.float32), np.array([[0, 1, 2]]))
    assert "out.xyz3" in str(error.value)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["broken.ply"]


def test_mesh_metrics_of_a_mesh_against_itself_are_zero(icosphere_path):
    V, F = meshgnn.read_mesh(icosphere_path)
    same = meshgnn.mesh_metrics(V, F, V, F, samples=2000)
    assert set(same) == {"cd", "hausdorff", "ne", "wa", "le", "holes", "edge_manifold"}
    assert same["cd"] == 0.0 and same["hausdorff"] == 0.0 and same["holes"] == 0
    assert same["edge_manifold"] is True
    V2, F2 = meshgnn.simplify(V, F, ratio=0.25)
    coarse = meshgnn.mesh_metrics(V, F, V2, F2, samples=2000)
    assert coarse["cd"] > 0.0 and coarse["hausdorff"] > 0.0
