#!/usr/bin/env bash
# clang-format (the committed .clang-format) and clang-tidy (the committed .clang-tidy) on the
# project's own sources; any finding fails. Usage: tools/lint.sh [build-dir with compile_commands]
set -euo pipefail
cd "$(dirname "$0")/.."
BUILD_DIR="${1:-build}"
mapfile -t sources < <(git ls-files '*.cpp' '*.hpp')
echo "lint: clang-format on ${#sources[@]} files"
clang-format --dry-run --Werror "${sources[@]}"
mapfile -t units < <(git ls-files '*.cpp')
echo "lint: clang-tidy on ${#units[@]} files"
# The compile commands are g++'s: clang does not know some of its warning flags (-Wno-restrict).
run-clang-tidy -p "$BUILD_DIR" -j "$(nproc)" -quiet -extra-arg=-Wno-unknown-warning-option \
  "${units[@]/#/$PWD/}" >"$BUILD_DIR/clang-tidy.log" 2>&1 || {
  grep -E "error:|warning:" "$BUILD_DIR/clang-tidy.log" | sort -u | head -100
  echo "lint: clang-tidy found problems (full log: $BUILD_DIR/clang-tidy.log)"
  exit 1
}
echo "lint: clean"
