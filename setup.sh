#!/usr/bin/env bash
# Sets up a Debian 12 machine for VTLoc and builds it: installs the Debian
# packages the project needs (only those missing, so a second run is quick),
# then configures and builds into build/. Safe to run again at any time.
set -euo pipefail
cd "$(dirname "$0")"

packages=(
  cmake g++ make pkg-config
  libvulkan-dev mesa-vulkan-drivers vulkan-validationlayers glslang-tools
  nlohmann-json3-dev catch2
  libglm-dev libtinygltf-dev libstb-dev libopencv-dev libpng-dev libjpeg-dev
  python3 python3-torch python3-torchvision python3-numpy python3-pil python3-pytest
  python3-tqdm libopenblas0-pthread
  pybind11-dev python3-dev
)

# --dev: also what the fuzzers and sanitizer builds need (CI; tests/fuzz/run.sh).
if [ "${1:-}" = "--dev" ]; then
  packages+=(clang libclang-rt-14-dev)
fi

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if ((${#missing[@]})); then
  echo "setup: installing ${missing[*]}"
  sudo=""
  if [ "$(id -u)" -ne 0 ]; then sudo="sudo"; fi
  $sudo apt-get update -q
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -q "${missing[@]}"
fi

# VTLOC_CMAKE_ARGS: extra configure options (CI passes -DVTLOC_WARNINGS_AS_ERRORS=ON).
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release ${VTLOC_CMAKE_ARGS:-}
cmake --build build -j"$(nproc)"
