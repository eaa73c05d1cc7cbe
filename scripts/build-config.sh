#!/usr/bin/env bash
# The one Release configuration that set-up and tests share (sourced by scripts/setup.sh and
# scripts/test.sh), so that the test command continues set-up's build instead of redoing it:
#   - the Python module (nanobind) is built in the same CMake build as the command line and the
#     tests (build/python is an importable package; .venv points at it), not compiled a second
#     time by `pip install .`;
#   - the CUDA backend is compiled here only where a GPU driver is present (where it can run);
#     elsewhere the test command compiles it once, in its sanitizer build, so that a broken kernel
#     cannot land. FOVEAL_CUDA=ON|OFF overrides the choice.
# Sets RELEASE_FLAGS and CUDA_HERE (ON/OFF); prints nothing.
gpu_driver_present() {
  command -v nvidia-smi > /dev/null 2>&1 || ldconfig -p 2> /dev/null | grep -q 'libcuda\.so\.1'
}
if [ -n "${FOVEAL_CUDA:-}" ]; then
  CUDA_HERE="$FOVEAL_CUDA"
elif gpu_driver_present; then
  CUDA_HERE=ON
else
  CUDA_HERE=OFF
fi
RELEASE_FLAGS=(-G Ninja -DCMAKE_BUILD_TYPE=Release -DFOVEAL_PYTHON=ON "-DPython_EXECUTABLE=$PWD/.venv/bin/python"
               "-DFOVEAL_CUDA=$CUDA_HERE")
