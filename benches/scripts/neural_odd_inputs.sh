#!/usr/bin/env bash
# Runs the neural mesh simplifier on odd meshes a user may bring, at 5, 20 and 50 %, and prints
# each run's exit status and JSON: a grid with random holes, a Möbius strip (not orientable), a
# sphere with a fin on a non-manifold edge, two coincident spheres, a sphere among 30 tiny
# closed parts. Every run must exit 0 (or with a one-line error), never panic or hang. Usage:
#   benches/scripts/neural_odd_inputs.sh MESHSIMPLIFY_BINARY [SECONDS_LIMIT] [WORK_DIR]
set -euo pipefail
bin=$1; limit=${2:-60}; work=${3:-bench-data/neural-odd}
mkdir -p "$work/out"
python3 - "$work" <<'PY'
import math, random, sys
d = sys.argv[1]
random.seed(1)

def write(name, vertices, faces):
    with open(f"{d}/{name}", "w") as f:
        f.writelines(f"v {x:.6f} {y:.6f} {z:.6f}\n" for x, y, z in vertices)
        f.writelines(f"f {a + 1} {b + 1} {c + 1}\n" for a, b, c in faces)

def sphere(rings, segments, radius=1.0, centre=(0.0, 0.0, 0.0)):
    """A closed UV sphere: two poles and rings × segments vertices between them."""
    cx, cy, cz = centre
    v = [(cx, cy, cz + radius)]
    for i in range(1, rings + 1):
        t = math.pi * i / (rings + 1)
        for j in range(segments):
            p = 2 * math.pi * j / segments
            v.append((cx + radius * math.sin(t) * math.cos(p), cy + radius * math.sin(t) * math.sin(p), cz + radius * math.cos(t)))
    v.append((cx, cy, cz - radius))
    south = len(v) - 1
    ring = lambda i, j: 1 + i * segments + j % segments
    f = [(0, ring(0, j), ring(0, j + 1)) for j in range(segments)]
    for i in range(rings - 1):
        for j in range(segments):
            f += [(ring(i, j), ring(i + 1, j), ring(i + 1, j + 1)), (ring(i, j), ring(i + 1, j + 1), ring(i, j + 1))]
    f += [(ring(rings - 1, j), south, ring(rings - 1, j + 1)) for j in range(segments)]
    return v, f

n = 60
grid_v = [(x / (n - 1), y / (n - 1), 0.05 * math.sin(6 * x / (n - 1)) * math.cos(5 * y / (n - 1))) for y in range(n) for x in range(n)]
grid_f = []
for y in range(n - 1):
    for x in range(n - 1):
        a = y * n + x
        if random.random() >= 0.1:
            grid_f += [(a, a + 1, a + n + 1), (a, a + n + 1, a + n)]
write("pierced.obj", grid_v, grid_f)

m, w = 200, 10
strip_v = []
for i in range(m):
    t = 2 * math.pi * i / m
    for k in range(w):
        s = -0.3 + 0.6 * k / (w - 1)
        strip_v.append(((1 + s * math.cos(t / 2)) * math.cos(t), (1 + s * math.cos(t / 2)) * math.sin(t), s * math.sin(t / 2)))
strip_f = []
for i in range(m):
    for k in range(w - 1):
        a, b = i * w + k, i * w + k + 1
        # The last row joins the first turned over: that is the half twist.
        c, e = ((i + 1) * w + k, (i + 1) * w + k + 1) if i + 1 < m else (w - 1 - k, w - 2 - k)
        strip_f += [(a, c, b), (b, c, e)]
write("mobius.obj", strip_v, strip_f)

v, f = sphere(40, 80)
a, b, _ = f[0]
write("finned.obj", v + [(2.0, 0.0, 0.0)], f + [(a, b, len(v))])

v, f = sphere(24, 48)
write("double.obj", v + v, f + [(a + len(v), b + len(v), c + len(v)) for a, b, c in f])

v, f = sphere(24, 48)
for _ in range(30):
    centre = tuple(random.gauss(0, 2) for _ in range(3))
    pv, pf = sphere(2, 4, 0.02, centre)
    f += [(a + len(v), b + len(v), c + len(v)) for a, b, c in pf]
    v += pv
write("confetti.obj", v, f)
PY
for mesh in pierced mobius finned double confetti; do
  for ratio in 0.05 0.2 0.5; do
    rc=0
    timeout "$limit" "$bin" simplify "$work/$mesh.obj" -o "$work/out/${mesh}_$ratio.obj" --ratio "$ratio" \
      --method neural --json > "$work/out/${mesh}_$ratio.json" 2>&1 || rc=$?
    printf "%-9s %-5s rc=%-3s %s\n" "$mesh" "$ratio" "$rc" "$(head -c 300 "$work/out/${mesh}_$ratio.json")"
  done
done
