#!/usr/bin/env python3
"""Side-by-side read speed of meshgnn, Open3D and trimesh on the same 1.3M-triangle files.

Inputs (icosphere(8) with seeded noise, 655 362 vertices, 1 310 720 triangles) are written by
`cargo run --release -p meshgnn-geometry --example write_bench_mesh` into bench-data/:
io_1m.ply (binary little endian), io_1m_ascii.ply, io_1m.obj.
Timed, wall clock, best of REPEATS runs, file already in the page cache (one untimed read
first):
  * Open3D  `o3d.io.read_triangle_mesh(path)`;
  * trimesh `trimesh.load(path, process=False)`;
  * meshgnn `read_mesh(path)`, timed inside the `read_mesh` example binary (built with
    `cargo build --release --example read_mesh -p meshgnn-geometry`), which prints seconds,
    so process start-up is not counted for anyone.
Prints MB/s (1 MB = 1e6 bytes of file) and meshgnn's speed-up over each peer.

Usage: pip install open3d trimesh numpy
       python3 benches/peers/io_peers.py [REPEATS] [DATA_DIR]
"""
import os
import subprocess
import sys
import time
from pathlib import Path

REPEATS = int(sys.argv[1]) if len(sys.argv) > 1 else 3
DATA = Path(sys.argv[2]) if len(sys.argv) > 2 else Path("bench-data")
BINARY = Path("target/release/examples/read_mesh")
FILES = ["io_1m.ply", "io_1m_ascii.ply", "io_1m.obj"]


def best_of(run):
    best = float("inf")
    for _ in range(REPEATS):
        start = time.perf_counter()
        counts = run()
        best = min(best, time.perf_counter() - start)
    return best, counts


def open3d_reader(path):
    import open3d as o3d

    def run():
        mesh = o3d.io.read_triangle_mesh(str(path))
        return len(mesh.vertices), len(mesh.triangles)

    return run


def trimesh_reader(path):
    import trimesh

    def run():
        mesh = trimesh.load(str(path), process=False)
        return len(mesh.vertices), len(mesh.faces)

    return run


def meshgnn(path):
    best = float("inf")
    counts = None
    for _ in range(REPEATS):
        out = subprocess.run([str(BINARY), str(path)], check=True, capture_output=True, text=True)
        words = out.stdout.split()
        counts = (int(words[1]), int(words[3]))
        best = min(best, float(words[5]))
    return best, counts


def main():
    if not BINARY.exists():
        sys.exit(f"missing {BINARY}: cargo build --release --example read_mesh -p meshgnn-geometry")
    print(f"{'file':<18}{'MB':>7}{'meshgnn MB/s':>14}{'Open3D MB/s':>13}{'trimesh MB/s':>14}"
          f"{'vs Open3D':>11}{'vs trimesh':>12}")
    for name in FILES:
        path = DATA / name
        size = os.path.getsize(path) / 1e6
        path.read_bytes()  # warm the page cache
        ours, ours_counts = meshgnn(path)
        row = [ours]
        for reader in (open3d_reader, trimesh_reader):
            try:
                seconds, counts = best_of(reader(path))
                if counts != ours_counts:
                    print(f"# {reader.__name__} read {counts}, meshgnn {ours_counts}")
                row.append(seconds)
            except Exception as error:  # a peer that cannot read the file is reported, not fatal
                print(f"# {reader.__name__} failed on {name}: {error}")
                row.append(float("nan"))
        speeds = [size / s for s in row]
        print(f"{name:<18}{size:>7.1f}{speeds[0]:>14.0f}{speeds[1]:>13.0f}{speeds[2]:>14.0f}"
              f"{row[1] / row[0]:>10.1f}x{row[2] / row[0]:>11.1f}x")


if __name__ == "__main__":
    main()
