#!/usr/bin/env bash
# Installs what prt needs on Debian 12 (as root), builds it with Ninja and ccache, and fetches the data.
# Safe to rerun: apt, the build and Makefile.data all skip work that is already done.
set -euo pipefail
cd "$(dirname "$0")/.."

packages=(
  cmake ninja-build ccache g++ make pkg-config git ca-certificates xz-utils
  libembree-dev libopenmesh-dev libopenexr-dev libopenimageio-dev openimageio-tools libceres-dev libtinygltf-dev
  pocl-opencl-icd ocl-icd-opencl-dev opencl-headers
  libtbb-dev libeigen3-dev libcli11-dev nlohmann-json3-dev libtomlplusplus-dev
  libxxhash-dev libgtest-dev libbenchmark-dev
  clang-14 libclang-rt-14-dev
  python3-numpy python3-matplotlib python3-openimageio
  slurm-wlm munge
  chromium
)
missing=()
for p in "${packages[@]}"; do dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "ok installed" || missing+=("$p"); done
command -v npm >/dev/null || missing+=(npm)
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

cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build build
make -f Makefile.data PRT=build/prt
