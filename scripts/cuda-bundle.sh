#!/usr/bin/env bash
# Build foveal with its CUDA backend on a Debian 12 machine set up by scripts/setup.sh (no GPU
# needed), and bundle the command line and the test binary with the Debian libraries they load, for
# a GPU machine whose system lacks those libraries and cannot install them (any x86-64 Linux with
# glibc ≥ 2.36 and an NVIDIA driver for CUDA 13; BENCHMARKS.md's GPU figures of the real-time loop
# were measured so, on an Ubuntu 24.04 image).
#
#   scripts/cuda-bundle.sh [BUNDLE.tar.xz]     (default: build-cuda/foveal-cuda.tar.xz)
#
# On the GPU machine, from a checkout of the same commit at the same path as here (the binaries
# find scenes/ and ../shared/data through it):
#   tar xJf foveal-cuda.tar.xz -C /tmp && /tmp/foveal-cuda/run foveal bench latency --device cuda …
#   /tmp/foveal-cuda/run foveal_tests --gtest_filter='Gpu*:*Gpu*:FrameRenderer.*:RealtimeLoop.*'
#
# nvcc: an installed CUDA 13, or CUDA 13.0 from NVIDIA's wheels on PyPI (nvidia-cuda-nvcc, -nvvm,
# -crt, -runtime, -cccl) unpacked into build-cuda/toolkit; the runtime is linked statically. OpenCV's image codecs link
# GDAL, whose own dependencies are about 130 MB of libraries; foveal never opens a GDAL raster, so
# the bundle carries a small libgdal.so.32 in its place whose functions stop the program with a
# message (GDALAllRegister, called when the codecs load, does nothing).
set -euo pipefail
cd "$(dirname "$0")/.."
root=$PWD
build=${FOVEAL_CUDA_BUILD:-$root/build-cuda}       # the build folder
bundle=${1:-$build/foveal-cuda.tar.xz}
# FOVEAL_CUDA_TOOLKIT: a CUDA 13 toolkit; default the one on PATH or in /usr/local/cuda when it is
# CUDA 13, else NVIDIA's wheels fetched into the build folder
toolkit=${FOVEAL_CUDA_TOOLKIT:-}
if [ -z "$toolkit" ]; then
  toolkit=$build/toolkit
  for nvcc in "$(command -v nvcc || true)" /usr/local/cuda/bin/nvcc; do
    if [ -n "$nvcc" ] && [ -x "$nvcc" ] && "$nvcc" --version | grep -q 'release 13\.'; then
      toolkit=$(dirname "$(dirname "$(readlink -f "$nvcc")")")
      break
    fi
  done
fi
# FOVEAL_CUDA_ARCHITECTURES: the GPUs compiled for (CMake's list; default the project's own)
mkdir -p "$build"

if [ ! -x "$toolkit/bin/nvcc" ] || [ ! -x "$toolkit/nvvm/bin/cicc" ]; then
  echo "fetching nvcc 13.0 from PyPI into $toolkit"
  wheels=$(mktemp -d)
  python3 -m pip download -q --no-deps --only-binary=:all: --platform manylinux2014_x86_64 --platform manylinux_2_17_x86_64 \
    --platform manylinux_2_12_x86_64 --platform manylinux2010_x86_64 -d "$wheels" \
    "nvidia-cuda-nvcc==13.0.*" "nvidia-nvvm==13.0.*" "nvidia-cuda-crt==13.0.*" "nvidia-cuda-runtime==13.0.*" "nvidia-cuda-cccl==13.0.*"
  python3 - "$wheels" "$toolkit" << 'EOF'
import pathlib, sys, zipfile
wheels, toolkit = pathlib.Path(sys.argv[1]), pathlib.Path(sys.argv[2])
for wheel in sorted(wheels.glob("*.whl")):
    with zipfile.ZipFile(wheel) as z:
        for info in z.infolist():
            parts = pathlib.PurePosixPath(info.filename).parts
            if len(parts) < 3 or parts[:2] != ("nvidia", "cu13") or info.is_dir():
                continue
            target = toolkit.joinpath(*parts[2:])
            target.parent.mkdir(parents=True, exist_ok=True)
            target.write_bytes(z.read(info))
            if parts[2] == "bin" or "bin" in parts[3:-1]:
                target.chmod(0o755)
EOF
  rm -rf "$wheels"
fi

cmake -S . -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Release -DFOVEAL_PYTHON=OFF -DFOVEAL_CUDA=ON \
  -DCMAKE_CUDA_COMPILER="$toolkit/bin/nvcc" -DCUDAToolkit_ROOT="$toolkit" -DCMAKE_CUDA_ARCHITECTURES="${FOVEAL_CUDA_ARCHITECTURES:-75-virtual;80-real;86-real;89-real;90-real}" > /dev/null
cmake --build "$build" --target foveal foveal_tests --parallel "$(nproc)"

stage=$(mktemp -d)
out=$stage/foveal-cuda
mkdir -p "$out/bin" "$out/lib"
cp "$build/foveal" "$build/tests/foveal_tests" "$out/bin/"
strip "$out/bin/"*
# GDAL's stand-in: the symbols OpenCV's codecs import from it
codecs=$(ldd "$build/foveal" | awk '$1 ~ /^libopencv_imgcodecs/ {print $3}')
gdal=$(ldd "$codecs" | awk '$1 ~ /^libgdal\.so/ {print $3}')
if [ -n "$gdal" ]; then
  {
    echo '#include <cstdio>'
    echo '#include <cstdlib>'
    k=0
    for s in $(comm -12 <(nm -D --undefined-only "$codecs" | awk '{print $2}' | sort -u) <(nm -D --defined-only "$gdal" | awk '{print $3}' | sort -u)); do
      if [ "$s" = GDALAllRegister ]; then body='{}'; else body='{ std::fputs("foveal-cuda: GDAL is not in this bundle\n", stderr); std::abort(); }'; fi
      echo "extern \"C\" void stand_in_$k() __asm__(\"$s\"); extern \"C\" void stand_in_$k() $body"
      k=$((k + 1))
    done
  } > "$stage/gdal.cpp"
  g++ -shared -fPIC -O1 -Wl,-soname,"$(basename "$gdal")" "$stage/gdal.cpp" -o "$out/lib/$(basename "$gdal")"
fi
# Every other library the binaries load, but the C and C++ runtimes (the GPU machine's own)
for round in 1 2 3; do
  LD_LIBRARY_PATH=$out/lib ldd "$out/bin/foveal" "$out/bin/foveal_tests" | awk '$2 == "=>" && $3 ~ /^\// {print $3}' | sort -u |
    while read -r lib; do
      case "$lib" in
        "$out"/* | */libc.so.* | */libm.so.* | */libstdc++.so.* | */libgcc_s.so.* | */libdl.so.* | */libpthread.so.* | */librt.so.*) ;;
        *) cp -L "$lib" "$out/lib/" ;;
      esac
    done
done
cat > "$out/run" << 'EOF'
#!/bin/sh
# Runs one of the bundle's programs with the bundle's libraries: run foveal|foveal_tests ARGS…
here=$(dirname "$(readlink -f "$0")")
program=$1
shift
LD_LIBRARY_PATH="$here/lib${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}" exec "$here/bin/$program" "$@"
EOF
chmod +x "$out/run"
libraries=$(ls "$out/lib" | wc -l)
tar cf - -C "$stage" foveal-cuda | xz -T0 -6 > "$bundle.partial"
mv "$bundle.partial" "$bundle"
rm -rf "$stage"
echo "wrote $bundle ($(du -h "$bundle" | cut -f1)): bin/foveal, bin/foveal_tests and $libraries libraries"
