#!/usr/bin/env python3
"""Area-uniform surface samples of every mesh in a folder, written as .xyz clouds.

Mesh vertices are not a point cloud of their surface: artist meshes and range maps put many
vertices where the triangles are small and few where they are large, and a simplification
scored against those vertices is scored on the mesher's density. The real-mesh rows of the
point-cloud benchmark (docs/results.md) therefore read clouds sampled uniformly by area, as
the synthetic shapes are.

    python benches/scripts/sample_surface_clouds.py IN_DIR OUT_DIR [--points 50000] [--seed 0]

Needs numpy and pymeshlab (to read .obj/.ply/.off alike).
"""
import argparse
import os

import numpy as np
import pymeshlab


def sample(vertices, faces, count, rng):
    a, b, c = (vertices[faces[:, i]] for i in range(3))
    area = 0.5 * np.linalg.norm(np.cross(b - a, c - a), axis=1)
    face = rng.choice(len(faces), size=count, p=area / area.sum())
    u, v = rng.random(count), rng.random(count)
    flip = u + v > 1
    u[flip], v[flip] = 1 - u[flip], 1 - v[flip]
    return a[face] + u[:, None] * (b[face] - a[face]) + v[:, None] * (c[face] - a[face])


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("input")
    parser.add_argument("output")
    parser.add_argument("--points", type=int, default=50000)
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()
    os.makedirs(args.output, exist_ok=True)
    names = [n for n in sorted(os.listdir(args.input)) if n.lower().endswith((".obj", ".ply", ".off"))]
    stems = [os.path.splitext(n)[0] for n in names]
    for i, name in enumerate(names):
        stem, ext = os.path.splitext(name)
        # two meshes with one stem (airplane.obj, airplane.ply) keep both, named by extension
        out_stem = stem if stems.count(stem) == 1 else f"{stem}_{ext[1:]}"
        ms = pymeshlab.MeshSet()
        ms.load_new_mesh(os.path.join(args.input, name))
        mesh = ms.current_mesh()
        rng = np.random.default_rng(args.seed + i)
        points = sample(mesh.vertex_matrix(), mesh.face_matrix(), args.points, rng)
        out = os.path.join(args.output, out_stem + ".xyz")
        np.savetxt(out, points, fmt="%.7g")
        print(f"{out}: {len(points)} points from {mesh.vertex_number()} vertices")


if __name__ == "__main__":
    main()
