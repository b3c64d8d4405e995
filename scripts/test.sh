#!/usr/bin/env bash
# The README's test command (after scripts/bootstrap.sh): installs what only the tests need, builds the rest of
# build/ (all targets) and runs the whole suite on that release build, then the
# sanitizer tree build-asan (clang 14, AddressSanitizer + UndefinedBehaviorSanitizer, libFuzzer coverage) with
# the reader, ray-casting and runtime-kernel tests under the sanitizers and a short fuzz smoke per harness.
# Sanitizer subset (to stay within CI's budget on 2 cores): test_core, test_bundle, test_mesh, test_image,
# test_raycast, test_runtime (the relight kernels' vector tail loads), and every tests/fuzz harness for
# PRT_FUZZ_SMOKE_SECONDS (default 10) each.
set -euo pipefail
cd "$(dirname "$0")/.."
jobs=${PRT_JOBS:-2}

# What only the tests need (scripts/bootstrap.sh installed what prt needs): clang 14 and its sanitizer runtimes
# for build-asan, an OpenCL platform for the glossy fits (PoCL), a private Slurm for the Slurm executor's test,
# Chromium for the viewer's test, Python for the figure scripts, the OpenImageIO tools.
packages=(
  clang-14 libclang-rt-14-dev pocl-opencl-icd slurm-wlm munge chromium
  python3-numpy python3-matplotlib python3-openimageio openimageio-tools
)
missing=()
for p in "${packages[@]}"; do dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "ok installed" || missing+=("$p"); done
if [ ${#missing[@]} -gt 0 ]; then
  export DEBIAN_FRONTEND=noninteractive
  apt-get update -qq
  apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi
# The browser viewer's npm packages (three, playwright-core) at the versions of viewer/package-lock.json; its test
# drives Debian's chromium above, never a downloaded browser.
[ -d viewer/node_modules/three ] && [ -d viewer/node_modules/playwright-core ] || (cd viewer && npm ci --no-audit --no-fund)
# npm packages the tests use (package-lock.json pins them): the Khronos glTF validator.
[ -d tests/bundle/gltf_validator/node_modules/gltf-validator ] ||
  npm ci --prefix tests/bundle/gltf_validator --no-audit --no-fund --loglevel=error

# Everything bootstrap.sh left out: the stage programs, the tests, the benchmarks.
cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build build
ctest --test-dir build --output-on-failure -j"$jobs"

sanitized=(test_core test_bundle test_mesh test_image test_raycast test_runtime)
fuzzers=(mesh_obj mesh_ply mesh_off mesh_stl mesh_gltf mesh_glb exr pipeline bundle npy lights shard fiv glossy adaptive)
cmake -S . -B build-asan -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_C_COMPILER=clang-14 \
  -DCMAKE_CXX_COMPILER=clang++-14 -DPRT_SANITIZE=ON -DPRT_FUZZ=ON \
  -DPRT_FUZZ_SMOKE_SECONDS="${PRT_FUZZ_SMOKE_SECONDS:-10}" >/dev/null
cmake --build build-asan -j"$jobs" --target "${sanitized[@]}" "${fuzzers[@]/#/fuzz_}"
labels=$(IFS='|'; echo "^(${sanitized[*]}|fuzz)$")
# Tests that run the prt binary need the whole tree: they run in build/ only.
ASAN_OPTIONS=detect_leaks=1 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
  ctest --test-dir build-asan --output-on-failure -j"$jobs" -L "$labels" -E "BinaryExits"
