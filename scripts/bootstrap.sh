#!/usr/bin/env bash
# The README's main job, part one: installs what prt and the default pipeline need on Debian 12 (as root), builds
# the `prt` driver with Ninja and ccache (only it: `prt run pipelines/default.toml` runs every stage as `prt STAGE`),
# and fetches the data. scripts/test.sh installs what only the tests need and builds the rest of the tree.
# Safe to rerun: apt, the build and Makefile.data all skip work that is already done.
set -euo pipefail
cd "$(dirname "$0")/.."

# Build and run time of prt; GoogleTest and Google Benchmark too, small, because the one build tree is configured
# with its tests (scripts/test.sh builds them). npm and node fetch the bunny (Makefile.data).
packages=(
  cmake ninja-build ccache g++ make pkg-config git ca-certificates xz-utils
  libembree-dev libopenmesh-dev libopenexr-dev libopenimageio-dev libceres-dev libtinygltf-dev libtinyobjloader-dev
  ocl-icd-opencl-dev opencl-headers
  libtbb-dev libeigen3-dev libcli11-dev nlohmann-json3-dev libtomlplusplus-dev
  libxxhash-dev libgtest-dev libbenchmark-dev
)
missing=()
for p in "${packages[@]}"; do dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "ok installed" || missing+=("$p"); done
command -v npm >/dev/null || missing+=(npm)
if [ ${#missing[@]} -gt 0 ]; then
  export DEBIAN_FRONTEND=noninteractive
  apt-get update -qq
  apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi

cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build build --target prt
make -f Makefile.data PRT=build/prt
