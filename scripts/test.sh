#!/usr/bin/env bash
# Build and run the whole test suite: a Release build, the Python package's tests (pip install .
# into .venv, pytest), then the C++ tests under AddressSanitizer
# and UndefinedBehaviorSanitizer, then each fuzz target for a bounded time.
# Usage: scripts/test.sh   (FUZZ_SECONDS=N to change each target's fuzzing time, default 20; 0 skips fuzzing)
set -euo pipefail
cd "$(dirname "$0")/.."
jobs="$(nproc)"

echo "== Release build and tests"
cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build build --parallel "$jobs"
ctest --test-dir build --output-on-failure --parallel "$jobs"

echo "== Python package: pip install . into .venv, then its tests (against the command line just built)"
scripts/python-env.sh
FOVEAL_CLI="$PWD/build/foveal" .venv/bin/python -m pytest -q python/tests

echo "== AddressSanitizer + UndefinedBehaviorSanitizer build and tests"
cmake -S . -B build-asan -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DFOVEAL_SANITIZE=ON -DFOVEAL_BUILD_BENCH=OFF >/dev/null
cmake --build build-asan --parallel "$jobs"
ASAN_OPTIONS=detect_leaks=1:abort_on_error=1 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
  ctest --test-dir build-asan --output-on-failure --parallel "$jobs"

seconds="${FUZZ_SECONDS:-20}"
if [ "$seconds" != 0 ]; then
  echo "== libFuzzer targets, ${seconds}s each"
  cmake -S . -B build-fuzz -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_COMPILER=clang++ \
    -DFOVEAL_FUZZ=ON -DFOVEAL_CUDA=OFF -DFOVEAL_BUILD_TESTS=OFF -DFOVEAL_BUILD_BENCH=OFF >/dev/null
  targets=$(cd fuzz && ls fuzz_*.cpp | sed 's/\.cpp$//')
  # shellcheck disable=SC2086
  cmake --build build-fuzz --parallel "$jobs" --target $targets
  for target in $targets; do
    mkdir -p "build-fuzz/corpus/$target"
    cp fuzz/corpus/"$target"/* "build-fuzz/corpus/$target/" 2>/dev/null || true
    if ! "build-fuzz/fuzz/$target" -max_total_time="$seconds" -rss_limit_mb=2048 -artifact_prefix=build-fuzz/ \
        "build-fuzz/corpus/$target" > "build-fuzz/$target.log" 2>&1; then
      tail -n 40 "build-fuzz/$target.log"
      echo "fuzz target $target failed (input saved under build-fuzz/)"
      exit 1
    fi
    tail -n 1 "build-fuzz/$target.log"
  done
fi
echo "all tests passed"
