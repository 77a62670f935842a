#!/usr/bin/env bash
# clang-format (the committed .clang-format) on every source, flake8 (the committed .flake8) on
# every Python file, and clang-tidy (the committed .clang-tidy) on the product's sources (as unity
# units configured in BUILD-DIR-lint, see below); any finding fails.
# Usage: tools/lint.sh [build-dir] [--all]
#   --all  clang-tidy on the tests and benchmarks too (CI leaves them out to stay within its time;
#          the tests are compiled with -Werror there).
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
[[ -d "$BUILD_DIR" ]] || {
  echo "lint: no $BUILD_DIR (configure that build first: its clang-tidy.log is written there)" >&2
  exit 2
}
mapfile -t sources < <(git ls-files '*.cpp' '*.hpp')
echo "lint: clang-format on ${#sources[@]} files"
clang-format --dry-run --Werror "${sources[@]}"
mapfile -t python < <(git ls-files '*.py')
echo "lint: flake8 on ${#python[@]} files"
flake8 "${python[@]}"
# clang-tidy reads unity sources: each target's files joined into one unit, so that the Fast DDS,
# Eigen and protobuf headers are parsed and matched once per target instead of once per file
# (about a third of the time). The header filter below then covers the joined .cpp files
# too, and a finding names the file and line it is in. A missing include still fails: the
# release build compiles file by file with -Werror.
LINT_DIR="$BUILD_DIR-lint"
extra=OFF
((ALL)) && extra=ON
cmake -S . -B "$LINT_DIR" -G Ninja -DCMAKE_BUILD_TYPE=Release -DCMAKE_UNITY_BUILD=ON \
  -DCMAKE_UNITY_BUILD_BATCH_SIZE=0 -DQSWARM_BUILD_TESTS="$extra" \
  -DQSWARM_BUILD_BENCH="$extra" >/dev/null
# A unity source includes .cpp files by design: that one check is off for them (the units' own
# directory holds this configuration; everything else is the repository's .clang-tidy).
printf 'InheritParentConfig: true\nChecks: -bugprone-suspicious-include\n' >"$LINT_DIR/.clang-tidy"
# Only the generated headers the sources include (protobuf, fastddsgen), nothing compiled.
mapfile -t generated < <(ninja -C "$LINT_DIR" -t targets all | sed -n 's/^\([^/][^:]*\.h\): CUSTOM_COMMAND$/\1/p')
ninja -C "$LINT_DIR" "${generated[@]}" >/dev/null
# The units: the unity sources, and the project's files built on their own (SKIP_UNITY_BUILD_
# INCLUSION); not generated code.
mapfile -t units < <(/usr/bin/python3 - "$LINT_DIR" "$PWD" <<'PY'
import json, os, sys
lint, src = sys.argv[1], sys.argv[2]
for e in json.load(open(os.path.join(lint, "compile_commands.json"))):
    f = os.path.join(e["directory"], e["file"])
    if "/Unity/unity_" in f or (f.startswith(src + "/") and not f.startswith(os.path.abspath(lint))):
        print(f)
PY
)
echo "lint: clang-tidy on ${#units[@]} units ($(git ls-files '*.cpp' | grep -c . ) files in all)"
dirs='common|agent|supervisor|launcher|discovery|preview|tools'
((ALL)) && dirs="$dirs|tests|bench"
# The compile commands are g++'s: clang does not know some of its warning flags (-Wno-restrict).
run-clang-tidy -p "$LINT_DIR" -j "$(nproc)" -quiet -extra-arg=-Wno-unknown-warning-option \
  -header-filter="^$PWD/($dirs)/.*\.(hpp|cpp)$" "${units[@]}" >"$BUILD_DIR/clang-tidy.log" 2>&1 || {
  grep -E "error:|warning:" "$BUILD_DIR/clang-tidy.log" | sort -u | head -100
  echo "lint: clang-tidy found problems (full log: $BUILD_DIR/clang-tidy.log)"
  exit 1
}
echo "lint: clean"
