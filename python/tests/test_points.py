"""Point operators: hand-computed answers, agreement with brute force, errors."""

import numpy as np
import pytest

import meshgnn


def test_fps_on_a_line_picks_the_far_end_then_the_middle():
    X = np.array([[0.0], [1.0], [2.0], [10.0]])
    np.testing.assert_array_equal(meshgnn.farthest_point_sampling(X, 3), [0, 3, 2])
    np.testing.assert_array_equal(meshgnn.farthest_point_sampling(X, 2, start=1), [1, 3])


def test_fps_in_3d_matches_brute_force_and_other_dimensions():
    X = np.random.default_rng(1).normal(size=(500, 3)).astype(np.float32)
    picked = meshgnn.farthest_point_sampling(X, 40)
    brute, distance = [0], np.full(len(X), np.inf)
    for _ in range(39):
        distance = np.minimum(distance, ((X - X[brute[-1]]) ** 2).sum(axis=1))
        brute.append(int(distance.argmax()))
    np.testing.assert_array_equal(picked, brute)
    # The same points padded with a zero column: a 4-d FPS picks the same.
    X4 = np.hstack([X, np.zeros((500, 1), np.float32)])
    np.testing.assert_array_equal(meshgnn.farthest_point_sampling(X4, 40), picked)


def test_weighted_sampling_never_picks_zero_weights_and_is_seeded():
    w = np.array([0.0, 1.0, 0.0, 2.0, 3.0, 0.0])
    picked = meshgnn.weighted_sampling(w, 3, seed=7)
    assert sorted(picked) == [1, 3, 4]
    big = np.random.default_rng(0).random(1000)
    np.testing.assert_array_equal(
        meshgnn.weighted_sampling(big, 100, seed=3), meshgnn.weighted_sampling(big, 100, seed=3)
    )
    assert len(set(meshgnn.weighted_sampling(big, 100, seed=3))) == 100


def test_knn_matches_brute_force():
    X = np.random.default_rng(2).random((300, 3)).astype(np.float32)
    indices, d2 = meshgnn.knn(X, 5)
    full = ((X[:, None, :] - X[None, :, :]) ** 2).sum(axis=2)
    np.fill_diagonal(full, np.inf)
    np.testing.assert_array_equal(indices, np.argsort(full, axis=1, kind="stable")[:, :5])
    np.testing.assert_allclose(d2, np.sort(full, axis=1)[:, :5], rtol=1e-5)
    q_indices, _ = meshgnn.knn(X, 1, queries=X[:10])
    np.testing.assert_array_equal(q_indices[:, 0], np.arange(10))


def test_chamfer_of_a_small_case():
    cd = meshgnn.chamfer(np.array([[0.0, 0, 0], [1, 0, 0]]), np.array([[0.0, 0, 0]]))
    assert cd == {
        "forward_sum": 1.0, "reverse_sum": 0.0, "forward_mean": 0.5, "reverse_mean": 0.0,
        "mean": 0.5,
    }


def test_point_cloud_metrics_rank_fps_above_a_corner(icosphere_path):
    X = meshgnn.read_points(icosphere_path)
    same = meshgnn.point_cloud_metrics(X, X)
    assert set(same) == {"cd", "nc", "ce", "re", "sdm", "sdm_nearest"} and same["cd"] == 0.0
    fps = X[meshgnn.farthest_point_sampling(X, 40)]
    corner = X[np.argsort(X[:, 0])[:40]]
    assert meshgnn.point_cloud_metrics(X, fps)["cd"] < meshgnn.point_cloud_metrics(X, corner)["cd"]


@pytest.mark.parametrize("method", ["neural", "sampler", "fps", "random", "tcp"])
def test_point_simplify_keeps_the_requested_count(icosphere_path, method):
    X = meshgnn.read_points(icosphere_path)
    indices, kept = meshgnn.point_simplify(X, points=40, method=method, seed=1)
    assert indices.shape == (40,) and kept.shape == (40, 3) and len(set(indices)) == 40
    if method != "neural":  # the neural refinement moves points; the sampler keeps them
        np.testing.assert_array_equal(kept, X[indices])
    again = meshgnn.point_simplify(X, points=40, method=method, seed=1)
    np.testing.assert_array_equal(again[0], indices)


def test_point_simplify_qem_needs_the_faces(icosphere_path):
    V, F = meshgnn.read_mesh(icosphere_path)
    indices, kept = meshgnn.point_simplify(V, points=42, method="qem", faces_of=F)
    assert indices.shape == (42,)
    with pytest.raises(ValueError):
        meshgnn.point_simplify(V, points=42, method="qem")


@pytest.mark.parametrize(
    "call, message",
    [
        (lambda: meshgnn.farthest_point_sampling(np.zeros((3, 3)), 4), "farthest_point_sampling"),
        (lambda: meshgnn.farthest_point_sampling(np.full((3, 3), np.nan), 2), "farthest_point_sampling"),
        (lambda: meshgnn.knn(np.zeros((3, 3)), 3), "knn"),
        (lambda: meshgnn.knn([[0.0, 0, 0]], 1), "X: expected a float32 or float64 array"),
        (lambda: meshgnn.chamfer(np.zeros((0, 3)), np.zeros((2, 3))), "chamfer"),
        (lambda: meshgnn.weighted_sampling(np.array([1.0, -1.0]), 1), "weighted_sampling"),
        (lambda: meshgnn.point_simplify(np.zeros((9, 3)), ratio=0.5, method="best"), 'method="best"'),
        (lambda: meshgnn.point_simplify(np.zeros((9, 3)), ratio=2.0, method="fps"), "ratio"),
    ],
)
def test_point_operators_reject_bad_input(call, message):
    with pytest.raises(ValueError) as error:
        call()
    assert message in str(error.value)
