#!/usr/bin/env python3
"""Counts the near-degenerate faces of OBJ meshes: area below 1e-6 of the longest edge squared
(caps, three vertices along a straight crease, whose cotangent weights make the Laplacian of
the LE metric indefinite). `meshsimplify info` counts only faces of zero area (1e-10); this is
the looser count docs/mesh_simplifier_model.md reports for the neural simplifier's output.

Usage: benches/scripts/sliver_faces.py OUT.obj...   (one line per file, then the total)
"""
import math
import sys


def read_obj(path):
    vertices, faces = [], []
    with open(path) as f:
        for line in f:
            words = line.split()
            if words[:1] == ["v"]:
                vertices.append([float(x) for x in words[1:4]])
            elif words[:1] == ["f"]:
                faces.append([int(w.split("/")[0]) - 1 for w in words[1:4]])
    return vertices, faces


def sub(a, b):
    return [a[0] - b[0], a[1] - b[1], a[2] - b[2]]


def cross_norm(a, b):
    c = [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
    return math.sqrt(sum(x * x for x in c))


def slivers(vertices, faces):
    count = 0
    for t in faces:
        a, b, c = (vertices[i] for i in t)
        longest = max(sum(x * x for x in e) for e in (sub(b, a), sub(c, b), sub(a, c)))
        if cross_norm(sub(b, a), sub(c, a)) / 2 < 1e-6 * longest:
            count += 1
    return count


total = 0
for path in sys.argv[1:]:
    vertices, faces = read_obj(path)
    n = slivers(vertices, faces)
    total += n
    print(f"{path}: {len(faces)} faces, {n} slivers")
print(f"total {total} slivers in {len(sys.argv) - 1} files")
