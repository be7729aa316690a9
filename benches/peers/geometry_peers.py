#!/usr/bin/env python3
"""Side-by-side timing of meshgnn's geometric operators against their usual peers.

Same inputs for everyone (written by `cargo run --release -p meshgnn-geometry --example
bench_inputs` into bench-data/):
  * Open3D `estimate_normals(KDTreeSearchParamKNN(15))` vs meshgnn
    `pca_normals_and_curvature(points, 15)` (which also returns the curvature of eq. 5.2)
    on 1M points;
  * scipy `eigsh(L, k=150, M=M, sigma=-1e-8, which='LM')` (ARPACK shift-invert, SuperLU)
    vs meshgnn `laplacian_eigenvectors(mesh, 150)` on the 41k-vertex bumpy sphere.
meshgnn is timed by `cargo run --release -p meshgnn-geometry --example time_ops`.
Each figure is the best of REPEATS runs, wall-clock seconds.

Usage: pip install open3d scipy numpy
       python3 benches/peers/geometry_peers.py [REPEATS] [DATA_DIR]
"""
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import scipy.io
import scipy.sparse.linalg

REPEATS = int(sys.argv[1]) if len(sys.argv) > 1 else 3
DATA = Path(sys.argv[2]) if len(sys.argv) > 2 else Path("bench-data")


def best_of(repeats, run):
    best = float("inf")
    result = None
    for _ in range(repeats):
        start = time.perf_counter()
        result = run()
        best = min(best, time.perf_counter() - start)
    return best, result


def open3d_normals():
    import open3d as o3d

    cloud = o3d.io.read_point_cloud(str(DATA / "points_1m.ply"))
    points = np.asarray(cloud.points).copy()

    def run():
        fresh = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(points))
        fresh.estimate_normals(o3d.geometry.KDTreeSearchParamKNN(15))
        return fresh

    seconds, _ = best_of(REPEATS, run)
    return seconds


def scipy_eigsh():
    l = scipy.io.mmread(str(DATA / "cotangent_l.mtx")).tocsc()
    m = scipy.io.mmread(str(DATA / "mass_m.mtx")).tocsc()
    seconds, (values, _) = best_of(
        min(REPEATS, 2), lambda: scipy.sparse.linalg.eigsh(l, k=150, M=m, sigma=-1e-8, which="LM")
    )
    return seconds, np.sort(values)


def meshgnn():
    out = subprocess.run(
        ["cargo", "run", "--quiet", "--release", "-p", "meshgnn-geometry", "--example",
         "time_ops", "--", str(REPEATS), str(DATA)],
        check=True, capture_output=True, text=True,
    ).stdout
    times = {}
    for line in out.splitlines():
        name, seconds = line.split()[:2]
        times[name] = float(seconds)
    return times, out


def main():
    ours, raw = meshgnn()
    print(raw.strip())
    o3d_seconds = open3d_normals()
    eig_seconds, eig_values = scipy_eigsh()
    print(f"scipy lambda_149 = {eig_values[-1]:.4f}")
    rows = [
        ("normals k=15, 1M points", "Open3D estimate_normals", o3d_seconds,
         ours["pca_normals_k15_1m"]),
        ("150 eigenpairs L x = lambda M x, 41k vertices", "scipy eigsh shift-invert",
         eig_seconds, ours["laplacian_eigenvectors_k150"]),
    ]
    print()
    print("| operation | peer | peer (s) | meshgnn (s) | peer / meshgnn |")
    print("|---|---|---|---|---|")
    for what, peer, theirs, mine in rows:
        print(f"| {what} | {peer} | {theirs:.3f} | {mine:.3f} | {theirs / mine:.2f}x |")


if __name__ == "__main__":
    main()
