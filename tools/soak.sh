#!/usr/bin/env bash
# Soak: 16 agent processes for 5 minutes (real time) under 30% message loss, 24 random link cuts
# and two kill/restart cycles. Passes when the swarm ends converged with the agreed value within
# 1e-6 m of the initial average, no process crashed (only the two planned SIGKILLs) or outlived
# the run, and the run record is complete.   Usage: tools/soak.sh [run-dir]
set -euo pipefail
cd "$(dirname "$0")/.."
tools/setup.sh build >/dev/null
DIR="${1:-build/soak-$(date +%Y%m%d-%H%M%S)}"
rm -rf "$DIR"
set +e
build/bin/swarm run scenarios/soak.txtpb --out "$DIR" --domain 13 --time-scale 1 \
  --loss 0.3 --random-cuts 24 --kill 5@60:90 --kill 11@180:210 2>&1 | tee "$DIR.log"
code=${PIPESTATUS[0]}
set -e
fail=0
# The run's numbers, read by the Python package (no file name or JSON spelled here).
report() { PYTHONPATH=python /usr/bin/python3 -m qswarm.report "$DIR" "$@"; }
check() { if eval "$2"; then echo "soak: ok   - $1"; else echo "soak: FAIL - $1"; fail=1; fi; }
check "swarm run exited 0 (converged)" '[[ $code -eq 0 ]]'
missing=$(report files.missing)
check "the run record has every file (missing: $missing)" '[[ $missing == - ]]'
check "the events end the run" '[[ $(report events.ended) == yes ]]'
drift=$(report average_drift_m)
check "agreed value within 1e-6 m of the initial average (drift $drift m)" "awk -v d=$drift 'BEGIN{exit !(d < 1e-6)}'"
kills=$(grep -c "killed by signal Killed" "$DIR.log" || true)
check "exactly the two planned SIGKILLs ($kills)" '[[ $kills -eq 2 ]]'
check "two restarts" '[[ $(grep -c "restarting agent" "$DIR.log") -eq 2 ]]'
check "no other abnormal exit" '! grep -E "agent [0-9]+ (killed by signal [^K]|exited with code [1-9])" "$DIR.log"'
orphans=0
IFS=, read -ra procs <<<"$(report pids)"
for p in "${procs[@]}"; do
  pid=${p##*:}
  if [[ -e /proc/$pid ]] && ! grep -q '^State:.*Z' "/proc/$pid/status" 2>/dev/null; then orphans=$((orphans + 1)); fi
done
check "no orphaned process ($orphans alive)" '[[ $orphans -eq 0 ]]'
fields=(converged convergence_time_s average_drift_m average_relative_error detect_s reconverge_s
  faults.injected.loss faults.injected.cut faults.kills faults.restarts faults.dropped)
IFS=$'\t' read -ra values <<<"$(report "${fields[@]}")"
for i in "${!fields[@]}"; do printf "%s %s  " "${fields[$i]}" "${values[$i]}"; done
echo
exit $fail
