#!/usr/bin/env bash
# Sets everything up (apt + build) and runs the main demo.
set -euo pipefail
cd "$(dirname "$0")/.."
tools/setup.sh build
./build/tools/swarm-preview "$@"
