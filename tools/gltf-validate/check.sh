#!/usr/bin/env bash
# Builds the morph-animation example of meshgnn-geometry, writes its GLB into a temporary
# folder (removed on exit) and runs the Khronos glTF-Validator on it (validate.cjs). Exits
# non-zero when the build fails or the validator reports an error.
#
# Usage: tools/gltf-validate/check.sh   (from anywhere; installs the npm package on first use)
# CARGO_PROFILE selects the cargo profile (default: testing, the one the tests build).
set -euo pipefail

here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
root="$(cd "$here/../.." && pwd)"
profile="${CARGO_PROFILE:-testing}"

if [ ! -d "$here/node_modules/gltf-validator" ]; then
  (cd "$here" && npm ci --no-audit --no-fund)
fi

work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT

(cd "$root" && cargo run --quiet --profile "$profile" -p meshgnn-geometry \
  --example morph_animation -- "$work/morph_animation.glb")
node "$here/validate.cjs" "$work/morph_animation.glb"
