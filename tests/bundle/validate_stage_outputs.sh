#!/usr/bin/env bash
# The Khronos glTF validator must report 0 errors on every bundle prt writes: the stages' outputs here, and the
# version 2 scene bundle (objects, instances, every component type) that test_bundle writes, and the scene bundles
# (version 3) of a textured glTF asset from assimp-testmodels (fetched by Makefile.data): meshprep, transfer, bake.
# Usage: validate_stage_outputs.sh PRT TEST_BUNDLE VALIDATOR_DIR ASSETS_DIR
set -euo pipefail
prt=$1 test_bundle=$2 validator=$3 assets=$4
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cd "$work"
"$prt" --quiet scene sphere -o sphere.glb
"$prt" --quiet scene box-room -o room.glb
"$prt" --quiet meshprep sphere.glb -o prepped.glb
"$prt" --quiet transfer room.glb -o transfer.glb --mode interreflected --samples 16 --bounces 1 --order 3
"$prt" --quiet bake sphere.glb -o baked.glb --resolution 32 --samples 8 --order 2
box="$assets/glTF2/BoxTextured-glTF/BoxTextured.gltf"
[ -f "$box" ] || { echo "missing $box: run make -f Makefile.data"; exit 1; }
"$prt" --quiet meshprep "$box" -o scene-prepped.glb
"$prt" --quiet transfer scene-prepped.glb -o scene-transfer.glb --mode interreflected --samples 16 --bounces 1 --order 3
"$prt" --quiet bake scene-prepped.glb -o scene-baked.glb --resolution 32 --samples 8 --order 2 --bounces 1
PRT_BUNDLE_TEST_KEEP="$work" "$test_bundle" --gtest_filter='BundleVersion2.ObjectsInstancesAndComponentTypesRoundTrip:BundleVersion2.VersionOneIsStillWrittenAndRead' >/dev/null
ls ./*.glb
node "$validator/validate.mjs" ./*.glb
