#!/usr/bin/env python3
"""`handy fit` on scans in an unknown orientation, unit and handedness: each given hand of a
`synth hands` folder is written as a point cloud aligned, turned by 150° about (1, 2, 3) and
scaled to metres, and turned by 100° about (0, 1, 0.3) and mirrored (a left hand); each is
fitted with `--aligned` (identity start) and with the default global start (docs/handy.md).
Printed per case: whether the fit was mirrored, R2S and S2R relative to the scan's
bounding-box diagonal (`--json`), and the per-vertex error to the true hand relative to the
same diagonal.

    cargo build --release -p handy
    pip install numpy plyfile
    python3 benches/scripts/hand_fit_orientations.py DATA hand_00021 hand_00042 ...
"""
import json
import os
import subprocess
import sys
import tempfile

import numpy as np
from plyfile import PlyData

HANDY = os.path.join(os.path.dirname(__file__), "..", "..", "target", "release", "handy")


def rotation(axis, degrees):
    a = np.asarray(axis, float) / np.linalg.norm(axis)
    t = np.radians(degrees)
    k = np.array([[0, -a[2], a[1]], [a[2], 0, -a[0]], [-a[1], a[0], 0]])
    return np.eye(3) + np.sin(t) * k + (1 - np.cos(t)) * k @ k


def vertices(path):
    v = PlyData.read(path)["vertex"]
    return np.stack([v[c] for c in "xyz"], 1).astype(float)


CASES = {
    "aligned": (np.eye(3), False, 1.0),
    "turned 150°, metres": (rotation([1, 2, 3], 150), False, 0.001),
    "turned 100°, mirrored": (rotation([0, 1, 0.3], 100), True, 1.0),
}


def main():
    data, names = sys.argv[1], sys.argv[2:]
    print("| hand | scan | start | mirrored | R2S / diagonal | S2R / diagonal | per-vertex / diagonal |")
    print("|---|---|---|---|---:|---:|---:|")
    with tempfile.TemporaryDirectory() as tmp:
        scan_path, fit_path = os.path.join(tmp, "scan.xyz"), os.path.join(tmp, "fit.ply")
        for name in names:
            v = vertices(os.path.join(data, f"{name}.ply"))
            for case, (r, mirror, scale) in CASES.items():
                scan = ((v - v.mean(0)) @ r.T + [10, -5, 3]) * scale
                if mirror:
                    scan[:, 0] *= -1
                np.savetxt(scan_path, scan, fmt="%.6f")
                diagonal = np.linalg.norm(scan.max(0) - scan.min(0))
                for start in ["--aligned", "global start"]:
                    args = [HANDY, "fit", scan_path, "-o", fit_path, "--symmetric",
                            "--estimate-scale", "--json"] + ([start] if start == "--aligned" else [])
                    out = json.loads(subprocess.run(args, capture_output=True, text=True,
                                                    check=True).stdout)
                    error = np.linalg.norm(vertices(fit_path) - scan, axis=1).mean() / diagonal
                    print(f"| {name} | {case} | {start} | {out['mirrored']} | "
                          f"{out['r2s_relative']:.4f} | {out['s2r_relative']:.4f} | {error:.4f} |",
                          flush=True)


if __name__ == "__main__":
    main()
