#!/usr/bin/env bash
# The whole test suite, printing how long each part took:
#   0. the sources' format (.clang-format);
#   1. the Release build (set-up's own, continued: the command line, the Python module, the tests)
#      and its tests, the layer check among them;
#   2. the Python package's tests (pytest) against that build's module and command line, and the
#      module's install rules (what `pip install .` packs);
#   3. the C++ tests under AddressSanitizer and UndefinedBehaviorSanitizer (with the CUDA backend
#      compiled, where nvcc is found and the Release build has not compiled it already);
#   4. each libFuzzer target for a bounded time.
# Usage: scripts/test.sh   (FUZZ_SECONDS=N per fuzz target, default 20, 0 skips fuzzing)
set -euo pipefail
cd "$(dirname "$0")/.."
jobs="$(nproc)"
source scripts/timing.sh

echo "== Format (.clang-format)"
scripts/check-format.sh
phase "format"

echo "== Python environment (.venv; a no-op where set-up made it)"
scripts/python-env.sh
source scripts/build-config.sh
phase "Python environment"

echo "== Release build (CUDA backend: $CUDA_HERE) and tests"
cmake -S . -B build "${RELEASE_FLAGS[@]}" > /dev/null
cmake --build build --parallel "$jobs"
phase "Release build"
ctest --test-dir build --output-on-failure --parallel "$jobs"
phase "Release tests"

echo "== Python package: its tests (the module of the Release build, against its command line) and install rules"
.venv/bin/foveal --version > /dev/null  # the command line from the virtual environment, as pip install . gives it
# (a foveal installed into .venv by `pip install .` comes first on the path and would be tested instead)
.venv/bin/python -c "import foveal, sys; sys.exit(0 if '/build/python/' in foveal.__file__ else \
'another foveal package shadows the build\'s module: ' + foveal.__file__ + ' (one installed by pip install .: .venv/bin/pip uninstall foveal)')"
FOVEAL_CLI="$PWD/build/foveal" .venv/bin/python -m pytest -q python/tests
rm -rf build/python-install
cmake --install build --component python --prefix build/python-install > /dev/null
PYTHONPATH="$PWD/build/python-install" .venv/bin/python -c "import foveal; assert '/python-install/' in foveal.__file__, foveal.__file__; \
foveal.Scene('builtin:plane'); print('  the installed package imports:', foveal.__file__)"
build/python-install/bin/foveal --version > /dev/null  # the command line is part of the package's install
echo "  the installed command line runs: $(build/python-install/bin/foveal --version)"
phase "Python tests"

echo "== AddressSanitizer + UndefinedBehaviorSanitizer build and tests"
sanitizer_cuda=ON
[ "$CUDA_HERE" = ON ] && sanitizer_cuda=OFF  # compiled once per run: the Release build has it
cmake -S . -B build-asan -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -g1 -DNDEBUG" \
  -DFOVEAL_SANITIZE=ON -DFOVEAL_BUILD_BENCH=OFF -DFOVEAL_CUDA=$sanitizer_cuda > /dev/null
cmake --build build-asan --parallel "$jobs"
phase "sanitizer build"
ASAN_OPTIONS=detect_leaks=1:abort_on_error=1 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
  ctest --test-dir build-asan --output-on-failure --parallel "$jobs"
phase "sanitizer tests"

seconds="${FUZZ_SECONDS:-20}"
if [ "$seconds" != 0 ]; then
  echo "== libFuzzer targets, ${seconds}s each"
  cmake -S . -B build-fuzz -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -g1 -DNDEBUG" \
    -DCMAKE_CXX_COMPILER=clang++ -DFOVEAL_FUZZ=ON -DFOVEAL_CUDA=OFF -DFOVEAL_BUILD_TESTS=OFF -DFOVEAL_BUILD_BENCH=OFF \
    -DFOVEAL_BUILD_APPS=OFF > /dev/null
  targets=$(cd fuzz && ls fuzz_*.cpp | sed 's/\.cpp$//')
  # shellcheck disable=SC2086
  cmake --build build-fuzz --parallel "$jobs" --target $targets
  phase "fuzz build"
  # One target per core at a time: each still fuzzes for its whole time on a core of its own
  fuzz_one() {
    local target="$1"
    mkdir -p "build-fuzz/corpus/$target"
    cp fuzz/corpus/"$target"/* "build-fuzz/corpus/$target/" 2>/dev/null || true
    if ! "build-fuzz/fuzz/$target" -max_total_time="$seconds" -rss_limit_mb=2048 -artifact_prefix="build-fuzz/$target-" \
        "build-fuzz/corpus/$target" > "build-fuzz/$target.log" 2>&1; then
      { tail -n 40 "build-fuzz/$target.log"; echo "fuzz target $target failed (input saved as build-fuzz/$target-*)"; } >&2
      return 1
    fi
    echo "  $target: $(tail -n 1 "build-fuzz/$target.log")"
  }
  export -f fuzz_one
  export seconds
  # shellcheck disable=SC2086
  if ! printf '%s\n' $targets | xargs -P "$jobs" -I{} bash -c 'fuzz_one "$1"' _ {}; then
    echo "fuzzing failed: a target above found a crash"
    exit 1
  fi
  phase "fuzzing"
fi
timing_summary "the test command"
echo "all tests passed"
