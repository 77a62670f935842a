#!/usr/bin/env bash
# `swarm plot` benchmark: one N-agent particle run of D simulated seconds (bench/scale.txtpb, which
# never counts as converged, so the record covers the whole duration), then `swarm plot` on it
# REPEAT times. Prints the record's size and the median wall time of `swarm plot`.
# Usage: bench/plot_bench.sh [N [D [REPEAT]]]   (default: 64 60 5)
set -euo pipefail
cd "$(dirname "$0")/.."
BIN=build/bin
[[ -x $BIN/swarm ]] || tools/setup.sh build >/dev/null
N=${1:-64}
D=${2:-60}
REPEAT=${3:-5}
OUT=build/bench-runs/plot-$N
rm -rf "$OUT"
mkdir -p "$(dirname "$OUT")"
# Time scale 2 keeps 64 processes within two cores; the record is in simulated time either way.
$BIN/swarm run bench/scale.txtpb --agents "$N" --seed 1 --duration "$D" --time-scale 2 \
  --out "$OUT" --domain 14 --quiet >/dev/null 2>&1 || true
# The run's numbers, read by the Python package (no file name spelled here).
report() { PYTHONPATH=python /usr/bin/python3 -m qswarm.report "$OUT" "$@"; }
rows=$(report telemetry.rows) || { echo "plot_bench: the run wrote no summary" >&2; exit 1; }
size=$(du -m --total "$OUT" | tail -1 | cut -f1)
times=()
for _ in $(seq "$REPEAT"); do
  rm -rf "$OUT/plots"
  start=$(date +%s%N)
  $BIN/swarm plot "$OUT" >/dev/null
  end=$(date +%s%N)
  times+=("$(awk -v ns=$((end - start)) 'BEGIN { printf "%.2f", ns / 1e9 }')")
done
median=$(printf "%s\n" "${times[@]}" | sort -n | awk '{ a[NR] = $1 } END { print a[int((NR + 1) / 2)] }')
echo "| agents | simulated s | telemetry rows | run directory [MB] | figures | swarm plot median [s] (of $REPEAT) | all runs [s] |"
echo "| --- | --- | --- | --- | --- | --- | --- |"
echo "| $N | $D | $rows | $size | $(ls "$OUT/plots" | wc -l) | $median | ${times[*]} |"
