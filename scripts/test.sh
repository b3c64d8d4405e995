#!/usr/bin/env bash
# The README's test command (after scripts/bootstrap.sh): the whole suite on the release build, then the
# sanitizer tree build-asan (clang 14, AddressSanitizer + UndefinedBehaviorSanitizer, libFuzzer coverage) with
# the reader and ray-casting tests under the sanitizers and a short fuzz smoke per harness.
# Sanitizer subset (to stay within CI's budget on 2 cores): test_core, test_bundle, test_mesh, test_image,
# test_raycast, and every tests/fuzz harness for PRT_FUZZ_SMOKE_SECONDS (default 10) each.
set -euo pipefail
cd "$(dirname "$0")/.."
jobs=${PRT_JOBS:-2}
ctest --test-dir build --output-on-failure -j"$jobs"

sanitized=(test_core test_bundle test_mesh test_image test_raycast)
fuzzers=(mesh_obj mesh_ply mesh_off mesh_stl mesh_gltf mesh_glb exr pipeline bundle npy fiv)
cmake -S . -B build-asan -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_C_COMPILER=clang-14 \
  -DCMAKE_CXX_COMPILER=clang++-14 -DPRT_SANITIZE=ON -DPRT_FUZZ=ON \
  -DPRT_FUZZ_SMOKE_SECONDS="${PRT_FUZZ_SMOKE_SECONDS:-10}" >/dev/null
cmake --build build-asan -j"$jobs" --target "${sanitized[@]}" "${fuzzers[@]/#/fuzz_}"
labels=$(IFS='|'; echo "^(${sanitized[*]}|fuzz)$")
# Tests that run the prt binary need the whole tree: they run in build/ only.
ASAN_OPTIONS=detect_leaks=1 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
  ctest --test-dir build-asan --output-on-failure -j"$jobs" -L "$labels" -E "BinaryExits"
