#!/usr/bin/env bash
# clang-format (the committed .clang-format) on every source, flake8 (the committed .flake8) on
# every Python file, and clang-tidy (the committed .clang-tidy) on the product's translation units;
# any finding fails.
# Usage: tools/lint.sh [build-dir with compile_commands] [--all]
#   --all  clang-tidy on the tests' units too (27 files, about 4 more minutes on two cores; CI
#          leaves them out to stay within its time; the tests are compiled with -Werror there).
set -euo pipefail
cd "$(dirname "$0")/.."
BUILD_DIR=build
ALL=0
for arg in "$@"; do
  case "$arg" in
  --all) ALL=1 ;;
  -*) echo "lint: unknown option $arg (usage: tools/lint.sh [build-dir] [--all])" >&2; exit 2 ;;
  *) BUILD_DIR="$arg" ;;
  esac
done
[[ -f "$BUILD_DIR/compile_commands.json" ]] || {
  echo "lint: no $BUILD_DIR/compile_commands.json (configure that build first)" >&2
  exit 2
}
mapfile -t sources < <(git ls-files '*.cpp' '*.hpp')
echo "lint: clang-format on ${#sources[@]} files"
clang-format --dry-run --Werror "${sources[@]}"
mapfile -t python < <(git ls-files '*.py')
echo "lint: flake8 on ${#python[@]} files"
flake8 "${python[@]}"
if ((ALL)); then
  mapfile -t units < <(git ls-files '*.cpp')
else
  mapfile -t units < <(git ls-files '*.cpp' ':!:tests/')
fi
echo "lint: clang-tidy on ${#units[@]} files"
# The compile commands are g++'s: clang does not know some of its warning flags (-Wno-restrict).
run-clang-tidy -p "$BUILD_DIR" -j "$(nproc)" -quiet -extra-arg=-Wno-unknown-warning-option \
  "${units[@]/#/$PWD/}" >"$BUILD_DIR/clang-tidy.log" 2>&1 || {
  grep -E "error:|warning:" "$BUILD_DIR/clang-tidy.log" | sort -u | head -100
  echo "lint: clang-tidy found problems (full log: $BUILD_DIR/clang-tidy.log)"
  exit 1
}
echo "lint: clean"
