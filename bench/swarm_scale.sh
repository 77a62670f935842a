#!/usr/bin/env bash
# Multi-process scaling benchmark: N agent processes and the supervisor over DDS on loopback, each
# size and scenario one `swarm run`. The scenarios:
#   all    N seeded random point agents on one sticky-proximity graph that soon links everyone
#          (bench/scale.txtpb, never converged, so it flies its whole duration): all-to-all;
#   range  N point agents from a random cube into a lattice over 4.5 m radio links
#          (bench/formation_range.txtpb, the cube scaled with N so the density stays that of
#          scenarios/formation_lattice64.txtpb): each agent has about a dozen neighbours, but the
#          swarm is dense enough that every agent is within reach of the cells every other one
#          listens to (docs/benchmarks.md);
#   grid   N point agents scattered up to 0.5 m about their slots of a flat grid, 3 m apart,
#          re-forming it over 3.5 m radio links (bench/formation_grid.txtpb): each links its four
#          grid neighbours and hears about eight agents, whatever N;
#   ring   N point agents on a fixed ring graph of degree 4 (bench/ring.txtpb): the traffic each
#          agent handles follows its degree, not N;
#   torus  the same agents on a fixed graph of degree 4 that mixes fast enough to agree: each
#          linked to the next id and to the id sqrt(N) on (a 16 x 16 torus at 256), until the
#          states are within 1 cm (it ends when they agree, or at its duration).
# Reports per run: CPU per agent (over its running time, start-up and discovery included), the
# same over its flight alone (barrier release to end) with its threads' wake-ups a second, late
# ticks, record age p50/p99 at the supervisor (its 10 Hz
# record stream, from each record's handing to its writer to the supervisor's receive thread), the
# age of the neighbours' state samples where the agents' transports accepted them (the median of
# the agents' p50s, the median and the largest of their p99s; bins 19 % wide), samples the
# agents accepted per second, agent CPU per accepted sample, discovery time (until the last agent's
# barrier released), how far apart the agents left their barriers (the last start less the first), the most DDS participants any agent knew at its end (every other one under
# simple discovery; through a Discovery Server only those it shares a topic with), RSS per agent,
# the supervisor's CPU (sampled from /proc every 0.2 s while it
# runs: its user + system time at the last sample over the run's wall time), the datagrams its
# sockets dropped at full receive buffers (/proc/net/udp, by the inodes of its sockets, at the last
# sample), the host's UDP receive-buffer errors during the run (/proc/net/snmp), the samples a
# second and agent CPU the run was predicted to take (its summary's load: `swarm calibrate`) beside
# the CPU its agents took in flight, and how the run ended.
# Usage: bench/swarm_scale.sh [N ...]        (default: 8 32 64 128)
# Environment: SCENARIOS="all range ring" DURATION=30 TIME_SCALE=1 RATE_HZ=50 BUILD_DIR=build
#              SECURE=1: DDS-Security on every process (a `swarm keys` keystore per size)
#              DISCOVERY=simple|server: transport.discovery (unset: the scenario's default, the
#              run's own Discovery Server above 32 plain agents)
#              RECEIVE=tick|threads: transport.receive (unset: the scenario's, tick by default)
#              PREDICT=1: fly nothing; print what `swarm inspect` predicts of each run's load
set -euo pipefail
cd "$(dirname "$0")/.."
BUILD=${BUILD_DIR:-build}
[[ -x $BUILD/bin/swarm ]] || tools/setup.sh "$BUILD" >/dev/null
SIZES=("$@")
((${#SIZES[@]})) || SIZES=(8 32 64 128)
read -ra KINDS <<<"${SCENARIOS:-all range ring}"
DURATION=${DURATION:-30}
TIME_SCALE=${TIME_SCALE:-1}
RATE_HZ=${RATE_HZ:-50}
OUT=$BUILD/bench-runs
mkdir -p "$OUT"
report() { PYTHONPATH=python /usr/bin/python3 -m qswarm.report "$@"; }
# Datagrams dropped at full receive buffers by the sockets of process $1, so far.
socket_drops() {
  local inodes
  inodes=$(find "/proc/$1/fd" -lname 'socket:*' -printf '%l ' 2>/dev/null | tr -dc '0-9 ')
  awk -v list="$inodes" 'BEGIN { n = split(list, a, " "); for (i = 1; i <= n; i++) want[a[i]] = 1 }
    FNR > 1 && ($10 in want) { d += $NF } END { print d + 0 }' /proc/net/udp /proc/net/udp6
}
# Adds field $2 to scenario $1's transport block (a second block would be refused).
transport_field() {
  if grep -q '^transport {' "$1"; then
    sed -i "s/^transport {/transport { $2/" "$1"
  else
    echo "transport { $2 }" >>"$1"
  fi
}
# The host's UDP receive-buffer errors so far (every socket, every process).
rcvbuf_errors() { awk '$1 == "Udp:" && $2 ~ /^[0-9]/ { print $6 }' /proc/net/snmp; }
# Agents 1..N about their slots of a GRID formation (ceil(sqrt(N)) columns, 3 m apart, by id),
# each displaced up to 0.5 m in x and y, at 10 m (seeded).
scattered_grid() {
  awk -v n="$1" 'BEGIN { srand(3); cols = 1; while (cols * cols < n) cols++
    for (i = 1; i <= n; i++) printf "agents { id: %d position { x: %.3f y: %.3f z: 10 } }\n", i,
      ((i - 1) % cols) * 3 + rand() - 0.5, int((i - 1) / cols) * 3 + rand() - 0.5 }'
}
# A FIXED graph on agents 1..N: each linked to the next id and to the id OFFSET on.
circulant() {
  awk -v n="$1" -v s="$2" 'BEGIN {
    printf "topology { policy: FIXED"
    for (i = 1; i <= n; i++) printf " edges { a: %d b: %d } edges { a: %d b: %d }",
      i, i % n + 1, i, (i + s - 1) % n + 1
    print " }" }'
}
if [[ ${PREDICT:-0} == 1 ]]; then
  printf "| agents | scenario | consensus [Hz] | time scale | predicted samples [1/s] | predicted agent CPU [cores] | exceeds the host | consensus rate that holds [Hz] |\n| --- | --- | --- | --- | --- | --- | --- | --- |\n"
fi
[[ ${PREDICT:-0} == 1 ]] || printf "| agents | scenario | consensus [Hz] | time scale | CPU per agent [%% of a core] | in flight [%% of a core] | wake-ups per agent in flight [1/s] | late ticks [%%] | record age p50 / p99 [ms] | neighbour sample age p50 / p99 (max) [ms] | accepted samples [1/s] | CPU per accepted sample [us] | discovery max [s] | start spread [s] | participants known [max] | RSS per agent [MB] | supervisor CPU [%% of a core] | supervisor socket drops | host UDP receive-buffer errors | predicted samples [1/s] | predicted / measured agent CPU [cores] | end |\n"
[[ ${PREDICT:-0} == 1 ]] || printf "| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |\n"
domain=${DOMAIN:-12}  # one run at a time: each reuses the domain the last one left
for kind in "${KINDS[@]}"; do
  for n in "${SIZES[@]}"; do
    dir="$OUT/scale-$kind-$n"
    rm -rf "$dir"
    scen="$OUT/scale-$kind-$n.txtpb"
    case $kind in
      all) sed "s/consensus_hz: 50/consensus_hz: $RATE_HZ/" bench/scale.txtpb >"$scen" ;;
      range)
        box=$(awk -v n="$n" 'BEGIN { printf "%.2f", 10 * (n / 64) ^ (1 / 3) }')
        sed -e "s/box_m: 10/box_m: $box/" -e "s/consensus_hz: 50/consensus_hz: $RATE_HZ/" \
          -e "s/physics_hz: 50/physics_hz: $RATE_HZ/" bench/formation_range.txtpb >"$scen"
        ;;
      grid)
        {
          sed -e "s/consensus_hz: 50/consensus_hz: $RATE_HZ/" -e "s/physics_hz: 50/physics_hz: $RATE_HZ/" \
            bench/formation_grid.txtpb
          scattered_grid "$n"
        } >"$scen"
        ;;
      ring)
        {
          sed "s/consensus_hz: 50/consensus_hz: $RATE_HZ/" bench/ring.txtpb
          circulant "$n" 2
        } >"$scen"
        ;;
      torus)
        {
          sed -e "s/consensus_hz: 50/consensus_hz: $RATE_HZ/" -e 's/name: "ring"/name: "torus"/' \
            -e 's/tolerance_m: 1e-12 hold_s: 1000/tolerance_m: 0.01 hold_s: 1/' bench/ring.txtpb
          circulant "$n" "$(awk -v n="$n" 'BEGIN { s = int(sqrt(n) + 0.5); print (s < 2 ? 2 : s) }')"
        } >"$scen"
        ;;
      *) echo "swarm_scale: unknown scenario $kind (all, range, grid, ring, torus)" >&2; exit 2 ;;
    esac
    [[ -n ${DISCOVERY:-} ]] && transport_field "$scen" "discovery: ${DISCOVERY^^}"
    [[ -n ${RECEIVE:-} ]] && transport_field "$scen" "receive: ${RECEIVE^^}"
    if [[ ${PREDICT:-0} == 1 ]]; then
      # What `swarm inspect` predicts for the run instead of flying it (its agents drawn as the run
      # would draw them: N of them, seed 3).
      sed -i -e "s/count: [0-9]*/count: $n/" -e "s/^seed: .*/seed: 3/" "$scen"
      "$BUILD"/bin/swarm inspect "$scen" --json | /usr/bin/python3 -c '
import json, sys
load = json.load(sys.stdin)["load"]
cal = load.get("calibrated", False)
cores = "%.2f" % load.get("predicted_cores", 0) if cal else "-"
over = ("yes" if load.get("exceeds") else "no") if cal else "-"
holds = "%.3g" % load.get("holdable_consensus_hz", 0) if cal else "-"
print("| %s | %s | %s | %s | %.0f | %s | %s | %s |" % (*sys.argv[1:5], load.get("deliveries_per_s", 0), cores, over, holds))
' "$n" "$kind" "$RATE_HZ" "$TIME_SCALE"
      continue
    fi
    secure=()
    if [[ ${SECURE:-0} == 1 ]]; then
      ks="$OUT/keys-$n"  # random agents are ids 1..N whatever the scenario
      if [[ ! -d $ks ]]; then
        echo "random_agents { count: $n }" >"$ks.txtpb"
        "$BUILD"/bin/swarm keys "$ks.txtpb" --out "$ks" >/dev/null
      fi
      secure=(--secure "$ks")
    fi
    agents=(--agents "$n")
    [[ $kind == grid ]] && agents=()  # its agents are listed: --agents would draw others
    "$BUILD"/bin/swarm run "$scen" "${agents[@]}" --seed 3 --duration "$DURATION" \
      --time-scale "$TIME_SCALE" --out "$dir" --domain "$domain" --quiet "${secure[@]}" \
      >"$dir.log" 2>&1 &
    launcher=$!
    sup_ticks=0 sup_pid="" sup_drops=0 errors_before=$(rcvbuf_errors) started=$(date +%s.%N)
    while kill -0 "$launcher" 2>/dev/null; do
      [[ -n $sup_pid ]] || sup_pid=$(awk -F, '$1 == "supervisor" { print $3 }' "$dir/processes.csv" 2>/dev/null || true)
      if [[ -n $sup_pid ]] && t=$(awk '{ print $14 + $15 }' "/proc/$sup_pid/stat" 2>/dev/null); then
        sup_ticks=$t
        sup_drops=$(socket_drops "$sup_pid")
      fi
      sleep 0.2
    done
    wait "$launcher" || true
    host_errors=$(($(rcvbuf_errors) - errors_before))
    sup_cpu=$(awk -v t="$sup_ticks" -v hz="$(getconf CLK_TCK)" -v s="$started" -v e="$(date +%s.%N)" \
      'BEGIN { printf "%.1f", 100 * t / hz / (e - s) }')
    if ! row=$(report "$dir" cpu_per_agent_pct flight_cpu_per_agent_pct flight_wakeups_per_s \
      late_ticks_pct messages.age_p50_ms \
      messages.age_p99_ms stats.arrival_age_p50_ms.median stats.arrival_age_p99_ms.median \
      stats.arrival_age_p99_ms.max delivered_per_s cpu_us_per_delivered stats.discovery_s.max start_spread_s \
      stats.participants.max stats.max_rss_kb.median load.deliveries_per_s load.calibrated load.predicted_cores \
      end_reason 2>/dev/null); then
      printf "| %d | %s | %s | %s | (no record: %s) |\n" "$n" "$kind" "$RATE_HZ" "$TIME_SCALE" \
        "$(tail -1 "$dir.log")"
      continue
    fi
    IFS=$'\t' read -r cpu fcpu wakes late p50 p99 np50 np99 np99max per_s cpu_per disc spread known rss pred_s calibrated pred_cores end <<<"$row"
    [[ $calibrated == true ]] || pred_cores=-  # no calibration of this host: nothing predicted
    [[ ${SECURE:-0} == 1 ]] && kind_shown="$kind, secure" || kind_shown=$kind
    [[ -n ${DISCOVERY:-} ]] && kind_shown="$kind_shown, ${DISCOVERY,,}"
    [[ -n ${RECEIVE:-} ]] && kind_shown="$kind_shown, receive ${RECEIVE,,}"
    awk -v n="$n" -v k="$kind_shown" -v hz="$RATE_HZ" -v ts="$TIME_SCALE" -v cpu="$cpu" -v fcpu="$fcpu" -v wakes="$wakes" -v late="$late" \
      -v p50="$p50" -v p99="$p99" -v np50="$np50" -v np99="$np99" -v np99max="$np99max" -v s="$per_s" -v cs="$cpu_per" -v d="$disc" -v sp="$spread" -v kn="$known" -v rss="$rss" \
      -v sup="$sup_cpu" -v sd="$sup_drops" -v he="$host_errors" -v ps="$pred_s" -v pc="$pred_cores" -v end="$end" '
      # "-": no agent heard a sample, or an agent build older than the flight columns
      function f(fmt, x) { return x == "-" ? "-" : sprintf(fmt, x) }
      BEGIN {
        printf "| %d | %s | %s | %s | %.2f | %s | %s | %.2f | %.1f / %.1f | %s / %s (%s) | %.0f | %.1f | %.2f | %s | %s | %.1f | %s | %s | %s | %.0f | %s / %s | %s |\n",
          n, k, hz, ts, cpu, f("%.2f", fcpu), f("%.0f", wakes), late, p50, p99, f("%.2f", np50), f("%.2f", np99), f("%.2f", np99max), s, cs, d, f("%.3f", sp), kn, rss / 1024, sup, sd, he, f("%.0f", ps), f("%.2f", pc), f("%.2f", fcpu * n / 100), end }'
  done
done
