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
    awk -v n="$n" -v mode="$mode" '
      FNR == 1 { files++ }
      $1 == "cpu_s" { cpu += $2 } $1 == "wall_s" { wall += $2 } $1 == "steps" { steps += $2 }
      $1 == "overruns" { over += $2 } $1 == "max_rss_kb" { rss += $2 }
      $1 == "discovery_s" && $2 > disc { disc = $2 }
      END {
        if (files == 0) { printf "| %d | %s | (no stats) |\n", n, mode; exit }
        printf "%d %s %.1f %.3f %.2f %.1f %.1f\n", n, mode, 100 * cpu / wall, (steps ? 100 * over / steps : 0), disc, rss / files / 1024, wall / files
      }' "$dir"/agent-*.stats > "$dir/agg.txt"
    read -r _ _ cpu over disc rss wall < "$dir/agg.txt"
    p50=$(grep -o '"age_p50_ms": [0-9.e+-]*' "$dir/summary.json" | awk '{printf "%.2f", $2}')
    p99=$(grep -o '"age_p99_ms": [0-9.e+-]*' "$dir/summary.json" | awk '{printf "%.2f", $2}')
    printf "| %d | %s | %s | %s %% | %s / %s | %s | %s | %s |\n" "$n" "${mode,,}" "$cpu" "$over" "$p50" "$p99" "$disc" "$rss" "$wall"
  done
done
