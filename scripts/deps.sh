#!/usr/bin/env bash
# Install foveal's build and test dependencies from Debian 12 packages (as root, or with sudo).
# Does nothing when they are all installed already.
set -euo pipefail
packages=(
  build-essential cmake ninja-build pkg-config clang libclang-rt-14-dev clang-format
  libembree-dev libtbb-dev libassimp-dev libglm-dev libcli11-dev nlohmann-json3-dev libfmt-dev
  zlib1g-dev libopenexr-dev libopencv-core-dev libopencv-imgproc-dev libopencv-imgcodecs-dev libopencv-features2d-dev
  libgtest-dev libgmock-dev libbenchmark-dev
  cppzmq-dev libmsgpack-cxx-dev ffmpeg jq
  slurmctld slurmd slurm-client munge
  libglfw3-dev libimgui-dev libgl-dev xvfb xauth libgl1-mesa-dri libglu1-mesa
  python3 python3-venv python3-dev python3-pip
)
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
[ "${#missing[@]}" -eq 0 ] && exit 0
echo "installing: ${missing[*]}"
SUDO=""
[ "$(id -u)" -eq 0 ] || SUDO="sudo"
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
