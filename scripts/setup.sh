#!/usr/bin/env bash
# Install every dependency (Debian 12 packages, as root), build foveal, and render the built-in
# scene with foveated AO. Usage: sudo scripts/setup.sh   (SKIP_APT=1 to skip the install step)
set -euo pipefail
cd "$(dirname "$0")/.."

if [ "${SKIP_APT:-0}" != 1 ]; then
  SUDO=""
  [ "$(id -u)" -eq 0 ] || SUDO="sudo"
  export DEBIAN_FRONTEND=noninteractive
  $SUDO apt-get update -qq
  $SUDO apt-get install -y -qq --no-install-recommends \
    build-essential cmake ninja-build pkg-config clang libclang-rt-14-dev \
    libembree-dev libtbb-dev libassimp-dev libglm-dev libcli11-dev nlohmann-json3-dev libfmt-dev \
    libopenexr-dev libopencv-core-dev libopencv-imgproc-dev libopencv-imgcodecs-dev \
    libgtest-dev libgmock-dev libbenchmark-dev >/dev/null
fi

cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build build --parallel "$(nproc)"

mkdir -p out
./build/foveal render --scene builtin:box --gaze 300,200 -o out/render.png --mask out/mask.png \
  --acuity-plot out/acuity.png --stats out/stats.json --aov ao=out/ao.pfm,depth=out/depth.exr
