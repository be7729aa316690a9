#!/usr/bin/env python3
"""Side-by-side timing of meshgnn's FPS against fpsample (QuickFPS, Han et al. 2023).

Runs our example (which writes the bumpy-sphere points to OUT_DIR/points_N.npy and prints
its own timings), then times fpsample's fastest variant, bucket_fps_kdline_sampling, on the
same points, sample counts and start index 0, checks our indices against fpsample's exact
fps_sampling where that is cheap (N*M <= 2e9; fpsample 1.0.2's bucket variants do not begin
at start_idx, so their sequences cannot be compared index by index), and prints a table with ratios (> 1: meshgnn faster).

    pip install fpsample numpy
    python3 benches/peers/fps_peers.py [OUT_DIR] [N,N,...] [RATIO,...]

Needs a release build: cargo build --release -p meshgnn-graph --example fps
"""
import os
import subprocess
import sys
import time

import fpsample
import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
out = sys.argv[1] if len(sys.argv) > 1 else os.path.join(ROOT, "bench-data")
sizes = sys.argv[2] if len(sys.argv) > 2 else "100000,1000000"
ratios = sys.argv[3] if len(sys.argv) > 3 else "0.01,0.05,0.2"
example = os.path.join(ROOT, "target", "release", "examples", "fps")

ours = {}
run = subprocess.run([example, out, sizes, ratios], check=True, capture_output=True, text=True)
for line in run.stdout.splitlines():
    parts = line.split()
    if len(parts) == 4 and parts[3] != "skipped":
        ours[(int(parts[0]), int(parts[1]), parts[2])] = float(parts[3])
    elif len(parts) == 2 and parts[0] == "threads":
        print(f"meshgnn threads: {parts[1]}")


def height(n):
    """Tree height from fpsample's guidance: bucket size 2**h, larger for larger clouds."""
    return 3 if n <= 20_000 else (5 if n <= 200_000 else 7)


print(f"{'N':>9} {'M':>8} {'fpsample s':>11} {'fast_fps s':>11} {'ratio':>7} {'exact s':>9} "
      f"{'weighted s':>11} {'same':>5}")
for n in [int(s) for s in sizes.split(",")]:
    pts = np.load(os.path.join(out, f"points_{n}.npy"))
    for r in [float(x) for x in ratios.split(",")]:
        m = max(1, round(n * r))
        h = height(n)
        best = float("inf")
        for _ in range(3):
            t = time.perf_counter()
            idx = fpsample.bucket_fps_kdline_sampling(pts, m, h=h, start_idx=0)
            best = min(best, time.perf_counter() - t)
        mine = np.fromfile(os.path.join(out, f"fps_{n}_{m}.u32"), dtype=np.uint32)
        if n * m <= 2e9:
            ref = np.asarray(fpsample.fps_sampling(pts, m, start_idx=0), dtype=np.int64)
            # "set": same points, order differs where two candidates tie exactly in f32
            # (we take the smaller index; fpsample does not).
            if np.array_equal(ref, mine.astype(np.int64)):
                same = "True"
            elif set(ref.tolist()) == set(mine.tolist()):
                same = "set"
            else:
                same = "False"
        else:
            same = "-"
        fast = ours.get((n, m, "fast_fps"), float("nan"))
        exact = ours.get((n, m, "exact_fps"))
        weighted = ours.get((n, m, "weighted"), float("nan"))
        exact_s = f"{exact:9.4f}" if exact is not None else "  skipped"
        print(f"{n:9d} {m:8d} {best:11.4f} {fast:11.4f} {best / fast:7.2f} {exact_s} "
              f"{weighted:11.4f} {same:>5}")
