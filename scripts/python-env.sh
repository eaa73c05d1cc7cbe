#!/usr/bin/env bash
# The Python environment: a virtual environment in .venv (Debian's python3, never the system's
# site-packages) with the test tools, pylsl and the parts of PsychoPy the examples use, and then
# foveal itself by `pip install .` (scikit-build-core compiles the C++ core; its build folder,
# build/python-*, is kept between runs).
# Usage: scripts/python-env.sh   (PYTHON=... to pick another interpreter ≥ 3.9)
set -euo pipefail
cd "$(dirname "$0")/.."
python="${PYTHON:-/usr/bin/python3}"
[ -x .venv/bin/python ] || "$python" -m venv .venv
pip=(.venv/bin/python -m pip --disable-pip-version-check -q)
"${pip[@]}" install -r python/requirements-test.txt -r examples/psychopy/requirements.txt
"${pip[@]}" install --no-deps "psychopy==2026.2.5"
"${pip[@]}" install .
