#!/usr/bin/env bash
# The Khronos glTF validator must report 0 errors on `prt adapt`'s bundles: ragged float/half, per-band u8/u16
# with per-vertex and per-cluster scales, and CPCA. Exits 77 (skipped) when the validator is not installed.
# Usage: validate_adapt_outputs.sh PRT VALIDATOR_DIR
set -euo pipefail
prt=$1 validator=$2
[ -d "$validator/node_modules/gltf-validator" ] || { echo "gltf-validator not installed"; exit 77; }
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cd "$work"
"$prt" --quiet scene box-room -o room.glb
"$prt" --quiet transfer room.glb -o transfer.glb --mode shadowed --samples 16 --order 3
for format in float half u16 u8; do
  "$prt" --quiet adapt transfer.glb -o "a_$format.glb" --order 2 --format "$format"
done
"$prt" --quiet adapt transfer.glb -o a_u8_cluster.glb --order 3 --format u8 --scales per-cluster --clusters 8
"$prt" --quiet adapt transfer.glb -o a_cpca.glb --order 3 --format cpca --clusters 4 --components 3
node "$validator/validate.mjs" ./a_*.glb
