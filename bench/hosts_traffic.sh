#!/usr/bin/env bash
# What crosses the network between hosts, per agent and per host each second. H hosts, each a
# network namespace on its own subnet routed through a hub that forwards unicast only (as the
# hosts tests build them), P agent processes on each flying all-to-all (edge-flow, 50 Hz, real
# time), the supervisor on host 0 and the Discovery Server on host 1, every process bound to its
# host's address. Once every agent has joined, the hub counts what each host sends to the others
# (iptables FORWARD counters) for a window of flight: samples between neighbours, records to the
# supervisor and discovery, all of it.
#
#   bench/hosts_traffic.sh [-w SECONDS] H:P [H:P ...]      (root; programs from $QSWARM_BIN or
#                                                           build/bin)
# Prints per H:P the median over hosts of: bytes and packets per agent per second, bytes per host
# per second, and bytes per sample to an off-host neighbour ((N - P) neighbours at 50 Hz).
set -euo pipefail
SRC="$(cd "$(dirname "$0")/.." && pwd)"
BIN="${QSWARM_BIN:-$SRC/build/bin}"
WINDOW=20
if [[ ${1:-} == -w ]]; then WINDOW=$2; shift 2; fi
(($# > 0)) || { echo "usage: $0 [-w SECONDS] H:P [H:P ...]" >&2; exit 2; }
[[ $(id -u) -eq 0 ]] || { echo "$0: needs root (network namespaces, iptables)" >&2; exit 2; }
P="qtr$$-"
WORK=$(mktemp -d /tmp/qswarm-traffic.XXXXXX)
pids=()
teardown() {
  ((${#pids[@]})) && kill -TERM "${pids[@]}" 2>/dev/null || true
  for pid in "${pids[@]}"; do wait "$pid" 2>/dev/null || true; done
  pids=()
  for ns in $(ip netns list | awk -v p="$P" 'index($1, p) == 1 { print $1 }'); do
    ip netns del "$ns"
  done
}
trap 'teardown; rm -rf "$WORK"' EXIT
addr() { echo "10.78.$(($1 + 1)).2"; }
# Runs on host $1, in place of the calling (sub)shell: started with `&`, $! is the program's pid.
on() { local h=$1; shift; exec nsenter --net="/run/netns/$P$h" -- "$@"; }
median() { sort -g | awk '{ v[NR] = $1 } END { print (NR % 2) ? v[(NR + 1) / 2] : (v[NR / 2] + v[NR / 2 + 1]) / 2 }'; }

printf '%-6s %6s %14s %14s %16s %18s\n' "H:P" agents "B/agent/s" "pkt/agent/s" "MB/host/s" "B/off-host sample"
for spec in "$@"; do
  H=${spec%%:*} PER=${spec##*:}
  N=$((H * PER))
  ((H >= 2 && PER >= 1)) || { echo "$0: $spec: need at least 2 hosts and 1 agent per host" >&2; exit 2; }
  ip netns add "${P}hub"
  ip -n "${P}hub" link set lo up
  ip netns exec "${P}hub" sysctl -qw net.ipv4.ip_forward=1
  for ((h = 0; h < H; ++h)); do
    ip netns add "$P$h"
    ip -n "$P$h" link add eth0 type veth peer name "p$h" netns "${P}hub"
    ip -n "$P$h" addr add "$(addr "$h")/24" dev eth0
    ip -n "$P$h" link set lo up
    ip -n "$P$h" link set eth0 up
    ip -n "${P}hub" addr add "10.78.$((h + 1)).1/24" dev "p$h"
    ip -n "${P}hub" link set "p$h" up
    ip -n "$P$h" route add 10.78.0.0/16 via "10.78.$((h + 1)).1"
    ip netns exec "${P}hub" iptables -A FORWARD -i "p$h" -j ACCEPT  # a counter per sending host
  done
  dir="$WORK/$spec" && mkdir -p "$dir"
  {
    echo "name: \"traffic\""
    for ((i = 1; i <= N; ++i)); do
      echo "agents { id: $i position { x: $(((i * 7) % 19)) y: $(((i * 5) % 17)) z: $((10 + (i * 3) % 13)) } }"
    done
    # Slow agreement and a tolerance it never holds: the swarm flies the whole window.
    cat <<EOF
gain: 0.01
weight { policy: UNWEIGHTED }
topology { policy: PROXIMITY threshold_m: 1000 }
convergence { tolerance_m: 1e-12 hold_s: 1000 }
duration_s: $((WINDOW + 120))
seed: 5
transport { domain_id: 3 }
EOF
  } >"$dir/s.txtpb"
  server="$(addr 1):11811"
  on 1 "$BIN/swarm-discovery" --servers "$server" --index 0 --domain 3 \
    --ready-file "$dir/ready" >"$dir/discovery.out" 2>&1 &
  pids+=($!)
  for _ in $(seq 300); do [[ -e $dir/ready ]] && break; sleep 0.1; done
  on 0 "$BIN/swarm-supervisor" --scenario "$dir/s.txtpb" --run-dir "$dir" --interface "$(addr 0)" \
    --discovery-server "$server" >"$dir/supervisor.out" 2>&1 &
  pids+=($!)
  for ((i = 1; i <= N; ++i)); do
    h=$(((i - 1) / PER))
    on "$h" "$BIN/swarm-agent" --scenario "$dir/s.txtpb" --id "$i" --run-dir "$dir" \
      --interface "$(addr "$h")" --discovery-server "$server" >"$dir/agent-$i.out" 2>&1 &
    pids+=($!)
  done
  joined=0
  for _ in $(seq 1800); do
    [[ -f $dir/events.csv ]] && joined=$(awk -F, 'NR > 1 && $2 == "join" { a[$3] } END { print length(a) }' "$dir/events.csv")
    ((joined >= N)) && break
    sleep 0.1
  done
  if ((joined < N)); then
    echo "$spec: only $joined of $N agents joined in 180 s ($dir kept)" >&2
    trap 'teardown' EXIT
    exit 1
  fi
  sleep 2  # past the start, into steady flight
  ip netns exec "${P}hub" iptables -Z FORWARD
  sleep "$WINDOW"
  ip netns exec "${P}hub" iptables -L FORWARD -v -x -n >"$dir/counters.txt"
  teardown
  awk -v w="$WINDOW" -v per="$PER" -v n="$N" '$3 == "ACCEPT" && $6 ~ /^p[0-9]+$/ {
      printf "%.0f %.1f %.3f %.0f\n", $2 / w / per, $1 / w / per, $2 / w / 1e6, $2 / w / per / ((n - per) * 50)
    }' "$dir/counters.txt" >"$dir/per_host.txt"
  printf '%-6s %6d %14s %14s %16s %18s\n' "$spec" "$N" \
    "$(cut -d' ' -f1 "$dir/per_host.txt" | median)" "$(cut -d' ' -f2 "$dir/per_host.txt" | median)" \
    "$(cut -d' ' -f3 "$dir/per_host.txt" | median)" "$(cut -d' ' -f4 "$dir/per_host.txt" | median)"
done
