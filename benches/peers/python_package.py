#!/usr/bin/env python3
"""The Python package measured side by side, in one run (docs/results.md "From Python").

    .venv/bin/maturin build --release -m python/Cargo.toml --target-dir target -o target/wheels-release
    .venv/bin/pip install target/wheels-release/meshgnn-*.whl fast-simplification pymeshlab
    cargo build --release -p meshsimplify
    cargo build --release -p meshgnn-graph --example qem
    target/release/examples/qem --make-bumpy 8 bench-data/bumpy8.ply
    .venv/bin/python benches/peers/python_package.py [--rounds 3] [--coma-repo DIR]

1. Call overhead: `meshsimplify simplify` (release binary) against `read_mesh` + `simplify` +
   `write_mesh` in this process, on the 1.31M-face bumpy sphere at 10%, rounds interleaved:
   the simplification alone (the CLI's `--json` `seconds` against the `simplify` call, which
   adds the array conversions and input checks) and end to end (process wall time against the
   three calls).
2. `simplify` against fast-simplification and pymeshlab on the same arrays (the call alone):
   time on the bumpy sphere, time and error (`meshgnn.mesh_metrics`: Chamfer and Hausdorff of
   50 000 surface samples, unit-sphere units) on the creature of data-fixtures.
3. `mesh_hierarchy(factors=(4, 4, 4, 4))` on ~5k- and ~50k-vertex templates (QEM decimations
   of the bumpy sphere), against COMA's Python preprocessing (`lib/mesh_sampling.py`'s
   `qslim_decimator_transformer`, the decimation psbody-based pipelines run) when
   `--coma-repo` points at a checkout of github.com/anuragranj/coma (a folder holding its
   `lib/`, e.g. `git archive HEAD lib | tar -x -C DIR`); its psbody/opendr imports
   are replaced by small numpy stand-ins, and only its first decimation (factor 4) is timed,
   stopped after `--coma-timeout` seconds: a lower bound on the whole pipeline, which also
   needs psbody's C++ AABB tree for the up-sampling.
4. The Dask example over a folder of synthetic meshes with 1 and 2 workers
   (`synth shapes -o bench-data/shapes200 --per-family 20 --resolution 48 --lidar 0`).
"""

import argparse
import json
import os
import signal
import statistics
import subprocess
import sys
import tempfile
import time
import types

import numpy as np
import scipy.sparse as sp

import meshgnn

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def median_str(values):
    return f"{statistics.median(values):.3f} s ({', '.join(f'{v:.3f}' for v in values)})"


def call_overhead(mesh_path, cli, rounds, scratch):
    print(f"\n## 1. Call overhead, {mesh_path}, ratio 0.1, {rounds} interleaved rounds")
    cli_total, cli_simplify, py_total, py_simplify = [], [], [], []
    for _ in range(rounds):
        start = time.perf_counter()
        out = subprocess.run(
            [cli, "simplify", mesh_path, "-o", os.path.join(scratch, "cli.ply"),
             "--ratio", "0.1", "--json", "--force"],
            check=True, capture_output=True, text=True,
        ).stdout
        cli_total.append(time.perf_counter() - start)
        cli_simplify.append(json.loads(out)["seconds"])
        start = time.perf_counter()
        V, F = meshgnn.read_mesh(mesh_path)
        middle = time.perf_counter()
        V2, F2 = meshgnn.simplify(V, F, ratio=0.1)
        py_simplify.append(time.perf_counter() - middle)
        meshgnn.write_mesh(os.path.join(scratch, "py.ply"), V2, F2)
        py_total.append(time.perf_counter() - start)
    print(f"faces {len(F)} -> {len(F2)}")
    print(f"simplification: CLI {median_str(cli_simplify)}, Python {median_str(py_simplify)}: "
          f"{statistics.median(py_simplify) / statistics.median(cli_simplify):.3f}x")
    print(f"end to end:     CLI {median_str(cli_total)}, Python {median_str(py_total)}: "
          f"{statistics.median(py_total) / statistics.median(cli_total):.3f}x")


def peers(mesh_path, ratios, rounds, with_error):
    import fast_simplification
    import pymeshlab

    V, F = meshgnn.read_mesh(mesh_path)
    V64, F32 = V.astype(np.float64), F.astype(np.int32)
    print(f"\n## 2. simplify against peers, {mesh_path} ({len(F)} faces), call only, {rounds} rounds")

    def ours(ratio):
        return meshgnn.simplify(V, F, ratio=ratio)

    def fast(ratio):
        return fast_simplification.simplify(V, F32, target_count=round(ratio * len(F)))

    def meshlab(ratio):
        ms = pymeshlab.MeshSet()
        ms.add_mesh(pymeshlab.Mesh(V64, F32))
        start = time.perf_counter()
        ms.meshing_decimation_quadric_edge_collapse(targetfacenum=round(ratio * len(F)))
        elapsed = time.perf_counter() - start
        m = ms.current_mesh()
        return m.vertex_matrix(), m.face_matrix(), elapsed

    for ratio in ratios:
        print(f"\nratio {ratio}: | method | faces | time | Chamfer | Hausdorff |")
        results = {}
        for name, run in (("meshgnn", ours), ("fast-simplification", fast), ("pymeshlab", meshlab)):
            times = []
            for _ in range(rounds):
                start = time.perf_counter()
                out = run(ratio)
                times.append(out[2] if len(out) == 3 else time.perf_counter() - start)
            results[name] = (out[0], out[1], times)
        base = statistics.median(results["meshgnn"][2])
        for name, (V2, F2, times) in results.items():
            error = ""
            if with_error:
                m = meshgnn.mesh_metrics(V, F, np.ascontiguousarray(V2, np.float32),
                                         np.ascontiguousarray(F2, np.int64), samples=50000)
                error = f"{m['cd']:.3e} | {m['hausdorff']:.3e}"
            print(f"| {name} | {len(F2)} | {median_str(times)} "
                  f"({statistics.median(times) / base:.2f}x ours) | {error} |")


def install_coma_stand_ins():
    """numpy stand-ins for the two psbody/opendr imports of COMA's mesh_sampling.py."""

    class Mesh:
        def __init__(self, v, f):
            self.v, self.f = np.asarray(v, np.float64), np.asarray(f, np.int64)

    def get_vertices_per_edge(v, f):
        edges = np.vstack([f[:, [0, 1]], f[:, [1, 2]], f[:, [2, 0]]])
        return np.unique(np.sort(edges, axis=1), axis=0)

    def get_vert_connectivity(v, f):
        e = get_vertices_per_edge(v, f)
        a = sp.csc_matrix((np.ones(len(e)), (e[:, 0], e[:, 1])), shape=(len(v), len(v)))
        return a + a.T

    psbody, psbody_mesh = types.ModuleType("psbody"), types.ModuleType("psbody.mesh")
    psbody_mesh.Mesh = Mesh
    opendr, topology = types.ModuleType("opendr"), types.ModuleType("opendr.topology")
    topology.get_vertices_per_edge = get_vertices_per_edge
    topology.get_vert_connectivity = get_vert_connectivity
    sys.modules.update({"psbody": psbody, "psbody.mesh": psbody_mesh, "opendr": opendr,
                        "opendr.topology": topology})
    return Mesh


def hierarchy(mesh_path, coma_repo, coma_timeout):
    V, F = meshgnn.read_mesh(mesh_path)
    print("\n## 3. mesh_hierarchy(factors=(4, 4, 4, 4)), spirals of length 9 on every level")
    for faces in (10_000, 100_000):
        TV, TF = meshgnn.simplify(V, F, faces=faces)
        start = time.perf_counter()
        h = meshgnn.mesh_hierarchy(TV, TF, factors=(4, 4, 4, 4))
        ours = time.perf_counter() - start
        print(f"template {len(TV)} vertices: meshgnn {ours:.3f} s, levels "
              f"{[len(v) for v in h.vertices]} vertices")
        if not coma_repo:
            continue
        Mesh = install_coma_stand_ins()
        sys.path.insert(0, os.path.join(coma_repo, "lib"))
        import mesh_sampling

        def stop(*_):
            raise TimeoutError

        signal.signal(signal.SIGALRM, stop)
        signal.alarm(coma_timeout)
        start = time.perf_counter()
        try:
            mesh_sampling.qslim_decimator_transformer(Mesh(TV, TF), factor=0.25)
            coma = f"{time.perf_counter() - start:.1f} s"
        except TimeoutError:
            coma = f"> {coma_timeout} s (stopped)"
        finally:
            signal.alarm(0)
        print(f"  COMA's Python decimation, first level only: {coma}")


def dask_batch(folder, scratch):
    print(f"\n## 4. Dask batch, {folder}, ratio 0.1")
    files = len([p for p in os.listdir(folder) if p.endswith(".ply")])
    for workers in (1, 2):
        summary = os.path.join(scratch, f"summary{workers}.json")
        subprocess.run(
            [sys.executable, os.path.join(ROOT, "examples", "python", "batch_simplify_dask.py"),
             folder, os.path.join(scratch, f"out{workers}"), "--ratio", "0.1",
             "--workers", str(workers), "--summary", summary],
            check=True, capture_output=True, text=True,
        )
        report = json.load(open(summary))
        busy = sum(r.get("seconds", 0.0) for r in report["results"])
        print(f"{workers} worker(s): {report['files']} of {files} files, {report['failed']} failed, "
              f"{report['seconds']:.2f} s wall (cluster start included), {busy:.2f} s in tasks")


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--mesh", default=os.path.join(ROOT, "bench-data", "bumpy8.ply"))
    parser.add_argument("--creature", default=os.path.join(ROOT, "data-fixtures", "examples", "creature.ply"))
    parser.add_argument("--cli", default=os.path.join(ROOT, "target", "release", "meshsimplify"))
    parser.add_argument("--shapes", default=os.path.join(ROOT, "bench-data", "shapes200"))
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--coma-repo")
    parser.add_argument("--coma-timeout", type=int, default=600)
    parser.add_argument("--sections", default="1,2,3,4", help="which of the four to run")
    args = parser.parse_args()
    sections = {int(s) for s in args.sections.split(",")}
    print(f"meshgnn {meshgnn.__version__}, numpy {np.__version__}, {os.cpu_count()} cores")
    with tempfile.TemporaryDirectory() as scratch:
        if 1 in sections:
            call_overhead(args.mesh, args.cli, args.rounds, scratch)
        if 2 in sections:
            peers(args.mesh, [0.1, 0.01], args.rounds, with_error=False)
            peers(args.creature, [0.1, 0.01], args.rounds, with_error=True)
        if 3 in sections:
            hierarchy(args.mesh, args.coma_repo, args.coma_timeout)
        if 4 in sections:
            dask_batch(args.shapes, scratch)


if __name__ == "__main__":
    main()
