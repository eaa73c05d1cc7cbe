#!/usr/bin/env bash
# Every C++ and CUDA source the repository tracks is formatted as .clang-format says (clang-format
# 14, Debian 12's). Prints the files that are not, with what would change, and exits 1; run
# `scripts/check-format.sh --fix` to format them in place.
set -euo pipefail
cd "$(dirname "$0")/.."
mapfile -t files < <(git ls-files '*.cpp' '*.h' '*.cu' '*.cuh')
if [ "${1:-}" = "--fix" ]; then
  clang-format -i "${files[@]}"
  exit 0
fi
bad=()
for f in "${files[@]}"; do
  clang-format --dry-run --Werror "$f" > /dev/null 2>&1 || bad+=("$f")
done
if [ "${#bad[@]}" -gt 0 ]; then
  for f in "${bad[@]}"; do
    echo "not formatted: $f"
    diff -u "$f" <(clang-format "$f") | head -n 20 || true
  done
  echo "${#bad[@]} file(s) are not formatted as .clang-format says: scripts/check-format.sh --fix"
  exit 1
fi
echo "format: ${#files[@]} sources as .clang-format says"
