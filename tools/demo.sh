#!/usr/bin/env bash
# Sets everything up (apt + build) and runs the main demo: the paper's time-varying weighted
# rendezvous as four agent processes plus a supervisor over DDS (loopback only), at time scale 2
# unless told otherwise. Extra arguments go to `swarm run`, e.g. tools/demo.sh --time-scale 1
set -euo pipefail
cd "$(dirname "$0")/.."
tools/setup.sh build
scale=(--time-scale 2)
for a in "$@"; do [[ $a == --time-scale* ]] && scale=(); done
exec ./build/bin/swarm run scenarios/demo.txtpb "${scale[@]}" "$@"
