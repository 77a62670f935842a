#!/usr/bin/env bash
# Sets everything up (apt + build) and runs the main demo: the paper's time-varying weighted
# rendezvous as four agent processes plus a supervisor over DDS (loopback only).
# Extra arguments go to `swarm run`, e.g. tools/demo.sh --time-scale 1
set -euo pipefail
cd "$(dirname "$0")/.."
tools/setup.sh build
exec ./build/bin/swarm run scenarios/demo.txtpb --time-scale 2 "$@"
