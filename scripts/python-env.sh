#!/usr/bin/env bash
# The Python environment: a virtual environment in .venv (Debian's python3, never the system's
# site-packages) with nanobind (the module's build), NumPy, the test tools, pylsl and the parts
# of PsychoPy the examples use, Snakemake (with its Slurm executor) and matplotlib for the study workflow. foveal itself is the module of the CMake build: a .pth file makes
# build/python (where `cmake --build build` puts foveal/ with its _core module) importable from
# .venv, and .venv/bin/foveal is that build's command line, so the set-up compiles the library once. (`pip install .` still builds a wheel on its own:
# docs/python.md.)
# Usage: scripts/python-env.sh   (PYTHON=... to pick another interpreter ≥ 3.9)
set -euo pipefail
cd "$(dirname "$0")/.."
python="${PYTHON:-/usr/bin/python3}"
[ -x .venv/bin/python ] || "$python" -m venv .venv
pip=(.venv/bin/python -m pip --disable-pip-version-check -q)
stamp=.venv/.foveal-requirements
wanted=$(cat python/requirements-test.txt examples/psychopy/requirements.txt workflows/study/requirements.txt | sha256sum | cut -c1-16)
if [ "$(cat "$stamp" 2> /dev/null)" != "$wanted" ]; then
  "${pip[@]}" install -r python/requirements-test.txt -r examples/psychopy/requirements.txt -r workflows/study/requirements.txt
  "${pip[@]}" install --no-deps "psychopy==2026.2.5"
  echo "$wanted" > "$stamp"
fi
site=$(.venv/bin/python -c 'import sysconfig; print(sysconfig.get_paths()["purelib"])')
echo "$PWD/build/python" > "$site/foveal-build.pth"
# ... and the command line of that build on the environment's PATH, as `pip install .` puts it there
ln -sfn "$PWD/build/foveal" .venv/bin/foveal
