#!/usr/bin/env bash
# Installs every Debian package Nestlight needs (idempotent), then configures and builds.
#   scripts/setup.sh                 Release build in build/
#   BUILD_DIR=... CMAKE_ARGS=... scripts/setup.sh
set -euo pipefail
cd "$(dirname "$0")/.."

PACKAGES=(
  build-essential cmake ninja-build pkg-config git
  clang-14 libclang-rt-14-dev            # libFuzzer targets
  clang-format-14                        # the format check (scripts/format.sh)
  libpcl-dev                             # PCD reading (behind one small target)
  libtbb-dev libzstd-dev libxxhash-dev libdraco-dev libeigen3-dev libnanoflann-dev
  nlohmann-json3-dev libcli11-dev libgtest-dev libbenchmark-dev
  libglm-dev libepoxy-dev                # GL maths, GL/EGL function loading
  libegl-dev libegl1-mesa-dev libegl-mesa0 libgl1-mesa-dri libosmesa6-dev  # headless GL (llvmpipe)
  libglfw3-dev libimgui-dev libstb-dev   # the window, its UI, PNG files
  libopenexr-dev libspdlog-dev           # EXR files, logging
  libembree-dev                          # the path-traced reference (Embree 3)
  xvfb xauth                             # the windowed viewer's test without a display
  glslang-tools                          # checks the GPU-only shaders that llvmpipe cannot compile
  python3 binutils xz-utils              # the GPU bundle and run scripts (scripts/gpu-*.sh)
)
# convert --mpi (docs/DISTRIBUTED.md): optional; NESTLIGHT_MPI=OFF builds without it.
if [ "${NESTLIGHT_MPI:-ON}" != "OFF" ]; then
  PACKAGES+=(openmpi-bin libopenmpi-dev)
fi

missing=()
for p in "${PACKAGES[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  echo "setup: installing ${missing[*]}"
  SUDO=""
  [ "$(id -u)" -ne 0 ] && SUDO="sudo"
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi

BUILD_DIR=${BUILD_DIR:-build}
# shellcheck disable=SC2086
cmake -S . -B "$BUILD_DIR" -G Ninja -DCMAKE_BUILD_TYPE=${BUILD_TYPE:-Release} \
  -DNESTLIGHT_MPI=${NESTLIGHT_MPI:-ON} ${CMAKE_ARGS:-} >/dev/null
# shellcheck disable=SC2086
ninja -C "$BUILD_DIR" ${TARGETS:-}
echo "setup: built $BUILD_DIR/nestlight"
