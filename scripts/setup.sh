#!/usr/bin/env bash
# Install every dependency (Debian 12 packages, as root), build foveal, and render the built-in
# scene with foveated AO. Usage: sudo scripts/setup.sh   (SKIP_APT=1 to skip the install step)
set -euo pipefail
cd "$(dirname "$0")/.."

[ "${SKIP_APT:-0}" = 1 ] || scripts/deps.sh

cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build build --parallel "$(nproc)"
# The Python package (pip install . into .venv) with the test tools and the PsychoPy examples' parts
scripts/python-env.sh

mkdir -p out
./build/foveal render --scene builtin:box --gaze 300,200 -o out/render.png --mask out/mask.png \
  --acuity-plot out/acuity.png --stats out/stats.json --aov ao=out/ao.pfm,depth=out/depth.exr
