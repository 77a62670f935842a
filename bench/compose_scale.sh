#!/usr/bin/env bash
# The compose swarm at N agents (podman-compose): how long replicas take to claim their ids and to
# pass the start barrier, and what each agent container costs (CPU, memory) while flying.
#
#   bench/compose_scale.sh N [N ...]       (needs the image: podman build -f docker/Dockerfile
#                                            -t localhost/qswarm:latest .)
# Prints one line per N: claim and discovery seconds (median, max over agents), per-container CPU
# % and cgroup memory (median over agents and 5 samples of `podman stats`), the agent process's
# RSS (VmRSS, median over agents), the supervisor's exit and convergence time.
set -euo pipefail
SRC="$(cd "$(dirname "$0")/.." && pwd)"
export CONTAINERS_CONF="$SRC/tests/compose/containers.conf"
RUNTIME="--runtime runc"
command -v runc >/dev/null || RUNTIME=""
# Every container keeps a kernel neighbour (ARP) entry for each peer it sends to, and the kernel
# counts those entries for the whole host against net.ipv4.neigh.default.gc_thresh3 (1024 by
# default): about (N + 2)^2 of them overflow it near N = 30, and then replicas discover only some
# of the others ("neighbor table overflow" in dmesg). As root, raise the limits for the bench and
# put them back afterwards; otherwise say what is needed.
NEIGH=/proc/sys/net/ipv4/neigh/default
max_n=0
for n in "$@"; do ((n > max_n)) && max_n=$n; done
need=$((2 * (max_n + 2) * (max_n + 2) + 1024))
saved=()
if (($(cat $NEIGH/gc_thresh3) < need)); then
  if [[ $(id -u) -eq 0 ]]; then
    saved=("$(cat $NEIGH/gc_thresh1)" "$(cat $NEIGH/gc_thresh2)" "$(cat $NEIGH/gc_thresh3)")
    echo $((need / 4)) >$NEIGH/gc_thresh1
    echo $((need / 2)) >$NEIGH/gc_thresh2
    echo "$need" >$NEIGH/gc_thresh3
    echo "host neighbour table limits raised to $need for the bench (were ${saved[2]})"
  else
    echo "warning: net.ipv4.neigh.default.gc_thresh3 is $(cat $NEIGH/gc_thresh3), $need needed for" \
      "$max_n containers: run as root or raise it (README, Docker compose)" >&2
  fi
fi
restore_neigh() {
  ((${#saved[@]} == 3)) || return 0
  echo "${saved[0]}" >$NEIGH/gc_thresh1
  echo "${saved[1]}" >$NEIGH/gc_thresh2
  echo "${saved[2]}" >$NEIGH/gc_thresh3
}
trap restore_neigh EXIT
printf '%-4s %-18s %-18s %-10s %-10s %-10s %-6s %s\n' N "claim_s p50/max" "discovery_s p50/max" \
  "cpu%/agent" "cgroup_MiB" "RSS_MiB" exit converged_at_s
for N in "$@"; do
  project="qswarm-bench-$N-$$"
  work=$(mktemp -d /tmp/qswarm-bench.XXXXXX)
  mkdir -p "$work/runs"
  compose=(podman-compose -p "$project" -f "$SRC/docker/docker-compose.yml")
  # Whatever happens, its containers, network and files go (down needs the same QSWARM_AGENTS).
  trap 'QSWARM_AGENTS="$N" QSWARM_RUNS="$work/runs" "${compose[@]}" down >/dev/null 2>&1 || true;
        podman network rm -f "${project}_swarm" >/dev/null 2>&1 || true; rm -rf "$work"; restore_neigh' EXIT
  QSWARM_AGENTS="$N" QSWARM_RUNS="$work/runs" QSWARM_USER="$(id -u):$(id -g)" \
    "${compose[@]}" --podman-run-args="$RUNTIME" up -d --no-build >"$work/up.log" 2>&1
  sup="${project}_supervisor_1"
  # Sample while the swarm flies: wait for every agent to be running, then 5 samples 2 s apart.
  for _ in $(seq 1 900); do
    running=$(for c in $(podman ps --filter "label=com.docker.compose.project=$project" \
      --filter label=com.docker.compose.service=agent --format '{{.Names}}'); do
      podman logs "$c" 2>&1 | grep -c "running at swarm time" || true; done | awk '{s += $1} END {print s + 0}')
    ((running >= N)) && break
    [[ "$(podman inspect -f '{{.State.Running}}' "$sup")" == true ]] || break
    sleep 1
  done
  for _ in 1 2 3 4 5; do
    podman stats --no-stream --format '{{.Name}} {{.CPUPerc}} {{.MemUsage}}' 2>/dev/null |
      grep "${project}_agent_" >>"$work/stats" || true
    sleep 2
  done
  for c in $(podman ps --filter "label=com.docker.compose.project=$project" \
    --filter label=com.docker.compose.service=agent --format '{{.Names}}'); do
    podman exec "$c" grep VmRSS /proc/1/status >>"$work/rss" 2>/dev/null || true
  done
  code=$(podman wait "$sup")
  for c in $(podman ps -a --filter "label=com.docker.compose.project=$project" \
    --filter label=com.docker.compose.service=agent --format '{{.Names}}'); do
    podman logs "$c" >>"$work/agents.log" 2>&1 || true
  done
  conv=$(podman logs "$sup" 2>&1 | sed -n 's/^converged at t = \([0-9.]*\) s.*/\1/p')
  run_dir=$(find "$work/runs" -mindepth 1 -maxdepth 1 -type d | head -1)
  /usr/bin/python3 - "$work" "$N" "$code" "${conv:--}" <<'PY'
import re, statistics, sys
work, n, code, conv = sys.argv[1], int(sys.argv[2]), sys.argv[3], sys.argv[4]
log = open(f"{work}/agents.log").read()
claim = [float(x) for x in re.findall(r"after ([0-9.]+) s of claiming", log)]
disc = [float(x) for x in re.findall(r"after ([0-9.]+) s of discovery", log)]
cpu, mem = [], []
rss = [int(l.split()[1]) / 1024 for l in open(f"{work}/rss")] if __import__("os").path.exists(f"{work}/rss") else []
for line in open(f"{work}/stats"):
    parts = line.split()
    cpu.append(float(parts[1].rstrip("%")))
    m = re.match(r"([0-9.]+)([kMG]i?B)", parts[2]) if len(parts) > 2 else None
    if not m:
        continue
    scale = {"kB": 1 / 1024, "KiB": 1 / 1024, "MB": 1, "MiB": 1, "GB": 1024, "GiB": 1024}[m.group(2)]
    mem.append(float(m.group(1)) * scale)
med = lambda v: f"{statistics.median(v):.2f}" if v else "-"
mx = lambda v: f"{max(v):.2f}" if v else "-"
print(f"{n:<4} {med(claim) + '/' + mx(claim):<18} {med(disc) + '/' + mx(disc):<18} "
      f"{med(cpu):<10} {med(mem):<10} {med(rss):<10} {code:<6} {conv}")
PY
  [[ -n $run_dir ]] && PYTHONPATH="$SRC/python" /usr/bin/python3 -m qswarm.report "$run_dir" end_reason \
    missing_agents 2>/dev/null | awk -F'\t' '{ print "     end:", $1, "| missing", $2 }' || true
  (trap - EXIT; QSWARM_AGENTS="$N" QSWARM_RUNS="$work/runs" "${compose[@]}" down >/dev/null 2>&1 || true)
  podman network rm -f "${project}_swarm" >/dev/null 2>&1 || true
  rm -rf "$work"
  trap restore_neigh EXIT
done
