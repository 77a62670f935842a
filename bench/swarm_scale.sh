#!/usr/bin/env bash
# Multi-process scaling benchmark: N agent processes + supervisor over DDS on loopback, in real
# time (time scale 1) for 30 s each. Reports per-agent CPU, physics-loop overruns, sample age
# p50/p99 at the supervisor, and discovery time (until every agent has heard every peer).
# Usage: bench/swarm_scale.sh [N ...]   (default: 8 16 32 64)
set -euo pipefail
cd "$(dirname "$0")/.."
BIN=build/bin
[[ -x $BIN/swarm ]] || tools/setup.sh build >/dev/null
SIZES=("$@")
((${#SIZES[@]})) || SIZES=(8 16 32 64)
OUT=build/bench-runs
mkdir -p "$OUT"
printf "| agents | mode | CPU per agent [%% of a core] | late ticks | sample age p50 / p99 [ms] | discovery max [s] | RSS per agent [MB] | converged-free run [s] |\n"
printf "| --- | --- | --- | --- | --- | --- | --- | --- |\n"
domain=150
for mode in PARTICLE QUADCOPTER; do
  for n in "${SIZES[@]}"; do
    dir="$OUT/scale-$mode-$n"
    rm -rf "$dir"
    scen="$OUT/scale-$mode.txtpb"
    sed "s/^mode: PARTICLE/mode: $mode/" bench/scale.txtpb > "$scen"
    $BIN/swarm run "$scen" --agents "$n" --seed 1 --duration 30 --time-scale 1 --out "$dir" \
      --domain $((domain++)) --quiet >/dev/null 2>&1 || true
    read -r cpu over disc rss wall p50 p99 < <(PYTHONPATH=python /usr/bin/python3 -m qswarm.report \
      "$dir" cpu_per_agent_pct late_ticks_pct stats.discovery_s.max stats.max_rss_kb.mean \
      stats.wall_s.mean messages.age_p50_ms messages.age_p99_ms) || { echo "| $n | ${mode,,} | (no record) |"; continue; }
    rss=$(awk -v k="$rss" 'BEGIN { printf "%.1f", k / 1024 }')
    printf "| %d | %s | %s | %s %% | %s / %s | %s | %s | %s |\n" "$n" "${mode,,}" "$cpu" "$over" "$p50" "$p99" "$disc" "$rss" "$wall"
  done
done
