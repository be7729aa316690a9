#!/usr/bin/env python3
"""Open edges of a simplified mesh that do not run along the input's border: edges with other
than two faces where a corner is not at a border vertex of the input ("off the border"), and
among them those with an end farther from the input's border, along the input's edges, than
the edge is long ("away from it"). WA counts every open edge, the input border's included;
these counts are what a simplifier left open beyond it, the figures
docs/mesh_simplifier_model.md ("Curled parts folded closed", "Cracks beside the border")
gives for the open real meshes. The first overstates: a simplifier that keeps a vertex next
to the border rather than on it runs its rim through it. The second understates: a crack
within an edge's length of the border is not counted (5 % of the airplane's faces dropped at
random: 9.9 % of the edges off the border, 7.1 % away from it; the input itself: 0 and 0).
Vertices are matched by position, so the output must keep input positions (`meshsimplify
simplify IN -o OUT.obj --method neural --keep-positions`; the faces are those of the run
without it). Input: OBJ or ASCII PLY; output: OBJ. The input's border is taken before any
welding, so seams of a mesh stored as patches count as border (a lower bound).

Usage: benches/scripts/open_edges_off_border.py INPUT OUT.obj...   (one line per output)
"""
import heapq
import math
import struct
import sys
from collections import Counter


def f32(x):
    return struct.unpack("f", struct.pack("f", float(x)))[0]


def read_obj(path):
    vertices, faces = [], []
    with open(path) as f:
        for line in f:
            words = line.split()
            if words[:1] == ["v"]:
                vertices.append(tuple(f32(x) for x in words[1:4]))
            elif words[:1] == ["f"]:
                corners = [int(w.split("/")[0]) - 1 for w in words[1:]]
                faces.extend([corners[0], corners[i], corners[i + 1]] for i in range(1, len(corners) - 1))
    return vertices, faces


def read_ascii_ply(path):
    with open(path) as f:
        counts, line = {}, ""
        while line != "end_header":
            line = f.readline().strip()
            words = line.split()
            if words[:1] == ["format"] and words[1] != "ascii":
                sys.exit(f"{path}: only ASCII PLY is read here")
            if words[:1] == ["element"]:
                counts[words[1]] = int(words[2])
        vertices = [tuple(f32(x) for x in f.readline().split()[:3]) for _ in range(counts["vertex"])]
        faces = []
        for _ in range(counts.get("face", 0)):
            corners = [int(w) for w in f.readline().split()[1:]]
            faces.extend([corners[0], corners[i], corners[i + 1]] for i in range(1, len(corners) - 1))
    return vertices, faces


def edge_counts(faces):
    counts = Counter()
    for t in faces:
        for i in range(3):
            a, b = t[i], t[(i + 1) % 3]
            counts[(min(a, b), max(a, b))] += 1
    return counts


def distance_to_border(vertices, faces, border):
    """Per input position: the shortest path along input edges to a border vertex (Dijkstra)."""
    neighbours = {}
    for t in faces:
        for i in range(3):
            a, b = vertices[t[i]], vertices[t[(i + 1) % 3]]
            length = math.dist(a, b)
            neighbours.setdefault(a, []).append((b, length))
            neighbours.setdefault(b, []).append((a, length))
    distance = {p: 0.0 for p in border}
    heap = [(0.0, p) for p in border]
    heapq.heapify(heap)
    while heap:
        d, p = heapq.heappop(heap)
        if d > distance[p]:
            continue
        for q, length in neighbours.get(p, []):
            if d + length < distance.get(q, math.inf):
                distance[q] = d + length
                heapq.heappush(heap, (d + length, q))
    return distance


def main():
    if len(sys.argv) < 3:
        sys.exit(__doc__)
    source = sys.argv[1]
    vertices, faces = (read_obj if source.endswith(".obj") else read_ascii_ply)(source)
    border = {vertices[v] for e, n in edge_counts(faces).items() if n != 2 for v in e}
    to_border = distance_to_border(vertices, faces, border)
    for path in sys.argv[2:]:
        out_vertices, out_faces = read_obj(path)
        counts = edge_counts(out_faces)
        open_edges = [e for e, n in counts.items() if n != 2]
        off = [e for e in open_edges if not all(out_vertices[v] in border for v in e)]
        # An edge of the output's rim may run through kept vertices next to the input's
        # border: away from it means an end farther from the border than the edge is long.
        away = [
            e
            for e in off
            if max(to_border.get(out_vertices[v], math.inf) for v in e)
            > math.dist(out_vertices[e[0]], out_vertices[e[1]])
        ]
        share = 100.0 * len(off) / max(len(counts), 1)
        away_share = 100.0 * len(away) / max(len(counts), 1)
        print(
            f"{path}: {len(open_edges)} open edges of {len(counts)}, {len(off)} off the input "
            f"border ({share:.2f} %), {len(away)} away from it ({away_share:.2f} %)"
        )


if __name__ == "__main__":
    main()
