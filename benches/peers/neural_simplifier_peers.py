#!/usr/bin/env python3
"""Seconds per mesh of the neural mesh simplifier (thesis ch. 6) against pymeshlab's quadric
edge collapse (MeshLab's QEM, the thesis' timing peer) and our own QEM, on the same files and
the same ratio, one process per run, interleaved (thesis claim: nearly flat time whatever
the size, below MeshLab's from 100k faces).

    pip install pymeshlab
    cargo build --release -p meshsimplify -p synth
    target/release/synth shapes --seed 0 -o /tmp/sizes48 --per-family 1 --resolution 48 --lidar 0
    (the same for 96, 192, 320; the creatures-b_00.ply of each)
    python3 benches/peers/neural_simplifier_peers.py [--ratio 0.1] [--rounds 3] MESH...

Our times are the `seconds` key of `meshsimplify simplify --json` (the simplification alone,
not reading or writing); pymeshlab's time the filter call alone. Medians over the rounds.
"""
import argparse
import json
import os
import statistics
import subprocess
import tempfile
import time

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
BINARY = os.environ.get("MESHSIMPLIFY", os.path.join(ROOT, "target", "release", "meshsimplify"))


def ours(path, ratio, method, out_dir):
    out = os.path.join(out_dir, f"{method}.ply")
    args = [BINARY, "simplify", path, "-o", out, "--ratio", str(ratio), "--method", method,
            "--json", "--force"]
    report = json.loads(subprocess.run(args, check=True, capture_output=True, text=True).stdout)
    return report["seconds"], report["input_faces"], report["output_faces"]


def meshlab(path, ratio):
    import pymeshlab

    ms = pymeshlab.MeshSet()
    ms.load_new_mesh(path)
    faces = ms.current_mesh().face_number()
    start = time.perf_counter()
    ms.meshing_decimation_quadric_edge_collapse(targetfacenum=round(ratio * faces))
    return time.perf_counter() - start, faces, ms.current_mesh().face_number()


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("meshes", nargs="+")
    parser.add_argument("--ratio", type=float, default=0.1)
    parser.add_argument("--rounds", type=int, default=3)
    args = parser.parse_args()
    print(f"ratio {args.ratio}, medians of {args.rounds} interleaved rounds (seconds)\n")
    print("| mesh | faces | neural | faces out | pymeshlab QEM | faces out | our QEM | neural / pymeshlab |")
    print("|---|---:|---:|---:|---:|---:|---:|---:|")
    with tempfile.TemporaryDirectory() as out_dir:
        for path in args.meshes:
            times = {"neural": [], "pymeshlab": [], "qem": []}
            for _ in range(args.rounds):
                seconds, faces, neural_out = ours(path, args.ratio, "neural", out_dir)
                times["neural"].append(seconds)
                seconds, _, meshlab_out = meshlab(path, args.ratio)
                times["pymeshlab"].append(seconds)
                seconds, _, _ = ours(path, args.ratio, "qem", out_dir)
                times["qem"].append(seconds)
            m = {k: statistics.median(v) for k, v in times.items()}
            print(f"| {os.path.basename(path)} | {faces} | {m['neural']:.2f} | {neural_out} | "
                  f"{m['pymeshlab']:.2f} | {meshlab_out} | {m['qem']:.3f} | "
                  f"{m['neural'] / m['pymeshlab']:.1f}× |")


if __name__ == "__main__":
    main()
