#!/usr/bin/env bash
# Drift of the agreed value and convergence time against message loss, for both laws:
# scenarios/faults_six.txtpb (6 agents, complete graph, unweighted, converged = 1e-8 m), random
# loss in every agent's receive path, 3 seeds per cell; medians reported.
# Usage: bench/fault_table.sh [seeds]      (BUILD_DIR=dir to use another build than build/)
#        RECEIVE=tick|threads: the agents' transport.receive (unset: the plan's, the tick here)
set -euo pipefail
cd "$(dirname "$0")/.."
BUILD=${BUILD_DIR:-build}
[[ -x $BUILD/bin/swarm ]] || tools/setup.sh "$BUILD" >/dev/null
SEEDS=${1:-3}
OUT=$BUILD/fault-table
mkdir -p "$OUT"
# A run's numbers, read by the Python package (no file name or JSON spelled here).
report() { PYTHONPATH=python /usr/bin/python3 -m qswarm.report "$@"; }
median() { sort -g | awk '{a[NR]=$1} END {print (NR % 2) ? a[(NR+1)/2] : (a[NR/2] + a[NR/2+1]) / 2}'; }
printf "| loss | law | agreed-value drift [m] (median) | relative error | convergence time [s] (median) |\n"
printf "| --- | --- | --- | --- | --- |\n"
domain=${DOMAIN:-15}  # one run at a time: each reuses the domain the last one left
scen=scenarios/faults_six.txtpb
if [[ -n ${RECEIVE:-} ]]; then
  scen="$OUT/faults_six-${RECEIVE,,}.txtpb"
  { cat scenarios/faults_six.txtpb; echo "transport { receive: ${RECEIVE^^} }"; } >"$scen"
fi
for loss in 0 0.1 0.3 0.5; do
  for law in edge-flow laplacian; do
    drifts=() times=() rels=()
    for seed in $(seq 1 "$SEEDS"); do
      dir="$OUT/$law-$loss-$seed"
      rm -rf "$dir"
      "$BUILD"/bin/swarm run "$scen" --law "$law" --loss "$loss" --seed "$seed" \
        --time-scale 4 --domain "$domain" --out "$dir" --quiet >/dev/null 2>&1 || true
      read -r drift rel t < <(report "$dir" average_drift_m average_relative_error \
        convergence_time_s)
      drifts+=("$drift") rels+=("$rel") times+=("$t")
    done
    d=$(printf "%s\n" "${drifts[@]}" | median)
    r=$(printf "%s\n" "${rels[@]}" | median)
    t=$(printf "%s\n" "${times[@]}" | median)
    printf "| %.0f %% | %s | %.2e | %.1e | %.2f |\n" "$(awk -v l=$loss 'BEGIN{print l*100}')" "$law" "$d" "$r" "$t"
  done
done
