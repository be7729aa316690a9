#!/usr/bin/env python3
"""Side-by-side timing of meshgnn's symmetric Chamfer distance against scipy's cKDTree.

Runs our example (which writes the random point sets to OUT_DIR/chamfer_{a,b}_N.f32 and prints
its own best-of-3 timings), then times scipy: build a cKDTree on each set and query the other
set against it with workers=-1 (all cores), best of 3. Checks that both give the same mean
squared distances and prints a table with ratios (> 1: meshgnn faster).

    pip install scipy numpy
    cargo build --release -p meshgnn-losses --example chamfer
    python3 benches/peers/chamfer_peers.py [OUT_DIR] [N,N,...]
"""
import os
import subprocess
import sys
import time

import numpy as np
from scipy.spatial import cKDTree

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
out = sys.argv[1] if len(sys.argv) > 1 else os.path.join(ROOT, "bench-data")
sizes = sys.argv[2] if len(sys.argv) > 2 else "100000,1000000"
example = os.path.join(ROOT, "target", "release", "examples", "chamfer")

ours = {}
run = subprocess.run([example, out, sizes], check=True, capture_output=True, text=True)
for line in run.stdout.splitlines():
    parts = line.split()
    if len(parts) == 4:
        ours[int(parts[0])] = (float(parts[1]), float(parts[2]), float(parts[3]))
    elif len(parts) == 2 and parts[0] == "threads":
        print(f"meshgnn threads: {parts[1]}, cores: {os.cpu_count()}")


def scipy_chamfer(a, b):
    ta, tb = cKDTree(a), cKDTree(b)
    da, _ = tb.query(a, k=1, workers=-1)
    db, _ = ta.query(b, k=1, workers=-1)
    return float(np.mean(da.astype(np.float64) ** 2)), float(np.mean(db.astype(np.float64) ** 2))


print(f"{'N':>9} {'meshgnn s':>10} {'scipy s':>9} {'ratio':>7} {'rel diff':>9}")
for n in [int(s) for s in sizes.split(",")]:
    a = np.fromfile(os.path.join(out, f"chamfer_a_{n}.f32"), dtype="<f4").reshape(-1, 3)
    b = np.fromfile(os.path.join(out, f"chamfer_b_{n}.f32"), dtype="<f4").reshape(-1, 3)
    a64, b64 = a.astype(np.float64), b.astype(np.float64)
    best = float("inf")
    for _ in range(3):
        t = time.perf_counter()
        f, r = scipy_chamfer(a64, b64)
        best = min(best, time.perf_counter() - t)
    mine_s, mine_f, mine_r = ours[n]
    diff = abs((mine_f + mine_r) - (f + r)) / (f + r)
    print(f"{n:>9} {mine_s:>10.4f} {best:>9.4f} {best / mine_s:>7.2f} {diff:>9.1e}")
