#!/usr/bin/env python3
"""`handy fit` on scans of closed and open hands: for every held-out hand (`test` and
`children` splits) of a `synth hands` folder whose gesture (manifest label) is fist, pinch or
an open one (flat, spread), two scans are made, both turned by 150° about (1, 2, 3) and scaled
to metres — **complete** (every vertex, fitted with `--symmetric`) and **partial** (the
vertices facing a scanner on the palm side, fitted with `--camera`) — and fitted with the
default global start. Printed: per gesture and scan, the mean over hands of the per-vertex
error to the true hand relative to its bounding-box diagonal, and of R2S / diagonal.

    cargo build --release -p handy
    pip install numpy plyfile
    python3 benches/scripts/hand_fit_gestures.py DATA [--model M] [--per-gesture 4]
"""
import argparse
import json
import os
import subprocess
import tempfile

import numpy as np
from plyfile import PlyData

from hand_fit_orientations import rotation

HANDY = os.path.join(os.path.dirname(__file__), "..", "..", "target", "release", "handy")
TURN_AXIS, TURN_DEGREES, METRES = [1, 2, 3], 150, 0.001
GROUPS = {"fist": ["fist"], "pinch": ["pinch"], "open": ["flat", "spread"]}


def mesh(path):
    ply = PlyData.read(path)
    v = ply["vertex"]
    faces = np.stack(ply["face"]["vertex_indices"])
    return np.stack([v[c] for c in "xyz"], 1).astype(float), faces


def vertex_normals(v, f):
    n = np.zeros_like(v)
    face_n = np.cross(v[f[:, 1]] - v[f[:, 0]], v[f[:, 2]] - v[f[:, 0]])
    for k in range(3):
        np.add.at(n, f[:, k], face_n)
    return n / np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-12)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("data")
    ap.add_argument("--model")
    ap.add_argument("--per-gesture", type=int, default=4)
    args = ap.parse_args()
    manifest = json.load(open(os.path.join(args.data, "dataset.json")))
    held_out = manifest["splits"]["test"] + manifest["splits"]["children"]
    r = rotation(TURN_AXIS, TURN_DEGREES)
    palm_camera = np.array([0.0, 0.0, -1.0])
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        scan_path, fit_path = os.path.join(tmp, "scan.xyz"), os.path.join(tmp, "fit.ply")
        for group, gestures in GROUPS.items():
            names = sorted(n for n in held_out if manifest["labels"][n]["gesture"] in gestures)
            for name in names[: args.per_gesture]:
                v, f = mesh(os.path.join(args.data, name))
                diagonal = np.linalg.norm(v.max(0) - v.min(0))
                facing = vertex_normals(v, f) @ palm_camera > 0.2
                for scan_kind, keep, extra in [
                    ("complete", np.ones(len(v), bool), ["--symmetric"]),
                    ("partial", facing, ["--camera=" + ",".join(f"{c:.6f}" for c in r @ palm_camera)]),
                ]:
                    scan = ((v[keep] - v.mean(0)) @ r.T + [10, -5, 3]) * METRES
                    np.savetxt(scan_path, scan, fmt="%.8f")
                    cmd = [HANDY, "fit", scan_path, "-o", fit_path, "--estimate-scale", "--json"]
                    cmd += extra + (["--model", args.model] if args.model else [])
                    out = json.loads(subprocess.run(cmd, capture_output=True, text=True,
                                                    check=True).stdout)
                    fitted, _ = mesh(fit_path)
                    truth = ((v - v.mean(0)) @ r.T + [10, -5, 3]) * METRES
                    error = np.linalg.norm(fitted - truth, axis=1).mean() / (diagonal * METRES)
                    rows.append((group, scan_kind, name, error, out["r2s_relative"]))
                    print(f"{group:5s} {scan_kind:8s} {name} age "
                          f"{manifest['labels'][name]['age']:4.1f}: per-vertex {error:.4f}, "
                          f"R2S {out['r2s_relative']:.4f} of the diagonal", flush=True)
    print("\n| gesture | scan | hands | per-vertex / diagonal | R2S / diagonal |")
    print("|---|---|---:|---:|---:|")
    for group in GROUPS:
        for scan_kind in ["complete", "partial"]:
            sel = [x for x in rows if x[0] == group and x[1] == scan_kind]
            if sel:
                print(f"| {group} | {scan_kind} | {len(sel)} | "
                      f"{np.mean([x[3] for x in sel]):.4f} | {np.mean([x[4] for x in sel]):.4f} |")


if __name__ == "__main__":
    main()
