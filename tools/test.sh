#!/usr/bin/env bash
# Sets everything up (apt + build) and runs the default test suite with ctest.
# Extra arguments go to ctest, e.g. tools/test.sh -L core
set -euo pipefail
cd "$(dirname "$0")/.."
tools/setup.sh build
cd build
ctest --output-on-failure --parallel "$(nproc)" --timeout 600 "$@"
