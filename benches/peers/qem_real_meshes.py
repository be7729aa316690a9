#!/usr/bin/env python3
"""QEM on a folder of real meshes, side by side with meshoptimizer (the `meshopt` crate,
through our `qem` example): faces in / target / out, error relative to meshoptimizer's, and
seconds, one row per mesh.

    cargo build --release -p meshgnn-graph --example qem
    python3 benches/peers/qem_real_meshes.py DIR [--ratio 0.1] [--json]

Error: the symmetric mean squared distance between dense lattice samples of the input and the
output (`mean_squared_rel` of the example, relative to the bounding-box diagonal squared).
`ratio` is ours / meshoptimizer's (below 1: ours is closer to the input).
"""
import argparse
import json
import os
import subprocess

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
EXAMPLE = os.environ.get("QEM_EXAMPLE", os.path.join(ROOT, "target", "release", "examples", "qem"))
MESH_EXTENSIONS = (".obj", ".ply", ".off", ".gltf", ".glb")

parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
parser.add_argument("folder")
parser.add_argument("--ratio", type=float, default=0.1)
parser.add_argument("--json", action="store_true", help="one JSON object per mesh")
args = parser.parse_args()


def run(path, meshopt):
    cmd = [EXAMPLE, path, "--ratio", str(args.ratio)] + (["--meshopt"] if meshopt else [])
    out = subprocess.run(cmd, check=True, capture_output=True, text=True).stdout
    return json.loads(out.strip().splitlines()[-1])


rows = []
for name in sorted(os.listdir(args.folder)):
    if not name.lower().endswith(MESH_EXTENSIONS):
        continue
    path = os.path.join(args.folder, name)
    ours, peer = run(path, False), run(path, True)
    target = round(args.ratio * ours["input_faces"])
    row = {
        "mesh": name,
        "input_faces": ours["input_faces"],
        "target": target,
        "faces": ours["output_faces"],
        "meshopt_faces": peer["output_faces"],
        "error": ours["mean_squared_rel"],
        "meshopt_error": peer["mean_squared_rel"],
        "error_ratio": ours["mean_squared_rel"] / max(peer["mean_squared_rel"], 1e-30),
        "seconds": ours["seconds"],
        "meshopt_seconds": peer["seconds"],
    }
    rows.append(row)
    if args.json:
        print(json.dumps(row), flush=True)

if not args.json:
    print(f"{'mesh':24} {'in':>8} {'target':>7} {'ours':>7} {'meshopt':>7} "
          f"{'err ratio':>9} {'s ours':>7} {'s mopt':>7}")
    for r in rows:
        print(f"{r['mesh']:24} {r['input_faces']:8} {r['target']:7} {r['faces']:7} "
              f"{r['meshopt_faces']:7} {r['error_ratio']:9.2f} {r['seconds']:7.3f} "
              f"{r['meshopt_seconds']:7.3f}")
    within = sum(r["faces"] <= r["target"] * 1.01 + 1 for r in rows)
    better = sum(r["error_ratio"] <= 1.0 for r in rows)
    print(f"{within}/{len(rows)} within 1% of the target; error <= meshoptimizer's on "
          f"{better}/{len(rows)}")
