#!/usr/bin/env bash
# Install every dependency (Debian 12 packages, as root; PyPI into .venv), build foveal, and render
# the built-in scene with foveated AO. Prints how long each part took.
# Usage: sudo scripts/setup.sh   (SKIP_APT=1 to skip the install step; FOVEAL_CUDA=ON|OFF to force
# the CUDA backend, which is otherwise built only where a GPU driver is present)
set -euo pipefail
cd "$(dirname "$0")/.."
source scripts/timing.sh

[ "${SKIP_APT:-0}" = 1 ] || scripts/deps.sh
phase "packages"
scripts/python-env.sh
phase "Python environment"

source scripts/build-config.sh
echo "== building foveal (Release; the Python module in the same build; CUDA backend: $CUDA_HERE)"
cmake -S . -B build "${RELEASE_FLAGS[@]}" > /dev/null
# The command line and the Python module: what the first picture and `import foveal` need (the
# test command builds the rest of this build: the tests and the micro-benchmarks)
cmake --build build --parallel "$(nproc)" --target foveal_cli foveal_core foveal_core_stub
phase "build"

mkdir -p out
./build/foveal render --scene builtin:box --gaze 300,200 -o out/render.png --mask out/mask.png \
  --acuity-plot out/acuity.png --stats out/stats.json --aov ao=out/ao.pfm,depth=out/depth.exr
.venv/bin/python -c "import foveal; print('  python   import foveal: ' + foveal.__file__)"
phase "first picture"

timing_summary "set-up"
echo "pictures: out/render.png (the foveated frame), out/mask.png (its AO budget), out/acuity.png (the acuity model)"
