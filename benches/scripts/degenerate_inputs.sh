#!/usr/bin/env bash
# Times pcsimplify on degenerate clouds (identical and collinear points) beside a random cloud
# of the same size, so a superlinear path shows as a ratio. Usage:
#   benches/scripts/degenerate_inputs.sh PCSIMPLIFY_BINARY [SECONDS_LIMIT] [WORK_DIR]
set -euo pipefail
bin=$1; limit=${2:-120}; work=${3:-bench-data/degenerate}
mkdir -p "$work/out"
python3 - "$work" <<'PY'
import random, sys
d = sys.argv[1]
def write(name, lines):
    with open(f"{d}/{name}", "w") as f:
        f.writelines(lines)
random.seed(7)
write("rand200k.xyz", (f"{random.random():.6f} {random.random():.6f} {random.random():.6f}\n" for _ in range(200_000)))
write("rand100k.xyz", (f"{random.random():.6f} {random.random():.6f} {random.random():.6f}\n" for _ in range(100_000)))
write("ident200k.xyz", ("0.125 -0.5 0.75\n" for _ in range(200_000)))
write("ident100k.xyz", ("0.125 -0.5 0.75\n" for _ in range(100_000)))
write("line200k.xyz", (f"{i} {2 * i} 0\n" for i in range(200_000)))
write("ident3m.obj", ("v 0.125 -0.5 0.75\n" for _ in range(3_000_000)))
write("rand3m.obj", (f"v {random.random():.6f} {random.random():.6f} {random.random():.6f}\n" for _ in range(3_000_000)))
write("ident1500k.obj", ("v 0.125 -0.5 0.75\n" for _ in range(1_500_000)))
PY
run() {
  local name=$1; shift
  local start; start=$(date +%s.%N)
  local rc=0; timeout "$limit" "$@" > "$work/out/$name.log" 2>&1 || rc=$?
  printf "%-16s rc=%-3s %7.2f s\n" "$name" "$rc" "$(echo "$(date +%s.%N) - $start" | bc)"
}
d=$work
run rand_eval      "$bin" eval "$d/rand200k.xyz" "$d/rand100k.xyz"
run rand_neural    "$bin" simplify "$d/rand200k.xyz" -o "$d/out/rand_neural.xyz" --ratio 0.5 --method neural
run rand_fps       "$bin" simplify "$d/rand200k.xyz" -o "$d/out/rand_fps.xyz" --ratio 0.5 --method fps
run ident_eval     "$bin" eval "$d/ident200k.xyz" "$d/ident100k.xyz"
run ident_neural   "$bin" simplify "$d/ident200k.xyz" -o "$d/out/ident_neural.xyz" --ratio 0.5 --method neural
run ident_fps      "$bin" simplify "$d/ident200k.xyz" -o "$d/out/ident_fps.xyz" --ratio 0.5 --method fps
run line_eval      "$bin" eval "$d/line200k.xyz" "$d/line200k.xyz"
run line_neural    "$bin" simplify "$d/line200k.xyz" -o "$d/out/line_neural.xyz" --ratio 0.5 --method neural
run rand3m_neural  "$bin" simplify "$d/rand3m.obj" -o "$d/out/rand3m_neural.xyz" --ratio 0.5 --method neural
run ident3m_neural "$bin" simplify "$d/ident3m.obj" -o "$d/out/ident3m_neural.xyz" --ratio 0.5 --method neural
run ident3m_fps    "$bin" simplify "$d/ident3m.obj" -o "$d/out/ident3m_fps.xyz" --ratio 0.5 --method fps
run ident3m_eval   "$bin" eval "$d/ident3m.obj" "$d/ident1500k.obj"
