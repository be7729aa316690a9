#!/usr/bin/env python3
"""Side-by-side QEM decimation timings: meshgnn and meshoptimizer (through our example
binary), pymeshlab `meshing_decimation_quadric_edge_collapse` and Open3D
`simplify_quadric_decimation`, on the same PLY and the same target face counts.

    pip install pymeshlab open3d
    cargo build --release -p meshgnn-graph --example qem
    target/release/examples/qem --make-bumpy 8 bench-data/bumpy8.ply
    python3 benches/peers/qem_peers.py [bench-data/bumpy8.ply] [0.1,0.01]

Times cover the decimation only (not file loading). Our example also prints the symmetric
Hausdorff and Chamfer distances (relative to the bounding-box diagonal) of its output.
"""
import json
import os
import subprocess
import sys
import time

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
mesh_path = sys.argv[1] if len(sys.argv) > 1 else os.path.join(ROOT, "bench-data", "bumpy8.ply")
ratios = [float(r) for r in (sys.argv[2] if len(sys.argv) > 2 else "0.1,0.01").split(",")]
example = os.environ.get("QEM_EXAMPLE", os.path.join(ROOT, "target", "release", "examples", "qem"))


def ours(ratio, meshopt):
    args = [example, mesh_path, "--ratio", str(ratio)] + (["--meshopt"] if meshopt else [])
    out = subprocess.run(args, check=True, capture_output=True, text=True).stdout
    return json.loads(out.strip().splitlines()[-1])


rows = []
for ratio in ratios:
    for meshopt in (False, True):
        r = ours(ratio, meshopt)
        rows.append((r["method"], ratio, r["output_faces"], r["seconds"],
                     f'H {r["hausdorff_rel"]:.2e} C {r["chamfer_rel"]:.2e}'))

try:
    import pymeshlab

    for ratio in ratios:
        ms = pymeshlab.MeshSet()
        ms.load_new_mesh(mesh_path)
        faces = ms.current_mesh().face_number()
        target = round(ratio * faces)
        start = time.perf_counter()
        ms.meshing_decimation_quadric_edge_collapse(targetfacenum=target, preserveboundary=True,
                                                    preservenormal=True, optimalplacement=True)
        seconds = time.perf_counter() - start
        rows.append(("pymeshlab", ratio, ms.current_mesh().face_number(), seconds, ""))
except ImportError as e:
    print(f"pymeshlab unavailable: {e}")

try:
    import open3d as o3d

    mesh = o3d.io.read_triangle_mesh(mesh_path)
    for ratio in ratios:
        target = round(ratio * len(mesh.triangles))
        start = time.perf_counter()
        out = mesh.simplify_quadric_decimation(target_number_of_triangles=target)
        seconds = time.perf_counter() - start
        rows.append(("open3d", ratio, len(out.triangles), seconds, ""))
except ImportError as e:
    print(f"open3d unavailable: {e}")

base = {ratio: s for (m, ratio, _, s, _) in rows if m == "meshgnn"}
print(f"{'method':>10} {'ratio':>6} {'faces':>8} {'seconds':>8} {'x meshgnn':>9}  quality")
for method, ratio, faces, seconds, quality in rows:
    print(f"{method:>10} {ratio:>6} {faces:>8} {seconds:>8.3f} {seconds / base[ratio]:>9.2f}  {quality}")
