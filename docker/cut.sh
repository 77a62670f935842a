#!/usr/bin/env bash
# Cuts one agent's container off the compose network for a while, then reconnects it at the same
# address (its DDS locators stay valid). The swarm records the silence: a departure and a return
# in events.csv, the agent's edges gone from graph.csv for the window.
#
#   docker/cut.sh AGENT_ID SECONDS [PROJECT]      (PROJECT: the compose project, default "docker")
#
# Environment: QSWARM_ENGINE=docker|podman (default: docker if its engine answers, else podman).
set -euo pipefail
if (($# < 2)); then
  echo "usage: $0 AGENT_ID SECONDS [PROJECT]" >&2
  exit 2
fi
agent="$1" seconds="$2" project="${3:-docker}"
[[ "$agent" =~ ^[1-9][0-9]*$ ]] || { echo "$0: AGENT_ID: expected a positive integer, got '$agent'" >&2; exit 2; }
[[ "$seconds" =~ ^[0-9]+([.][0-9]+)?$ ]] || { echo "$0: SECONDS: expected a number, got '$seconds'" >&2; exit 2; }
engine="${QSWARM_ENGINE:-}"
if [[ -z "$engine" ]]; then
  if docker info >/dev/null 2>&1; then engine=docker; else engine=podman; fi
fi

# The container flying the agent: each replica logs "replica NONCE ... flies as agent ID".
container=""
for c in $($engine ps --filter "label=com.docker.compose.project=$project" \
  --filter "label=com.docker.compose.service=agent" --format '{{.Names}}'); do
  # (grep reads all of the log: -q would stop early and fail the pipeline with SIGPIPE)
  if (($($engine logs "$c" 2>&1 | grep -c "flies as agent $agent\$") > 0)); then
    container="$c"
    break
  fi
done
if [[ -z "$container" ]]; then
  echo "$0: no running container of project '$project' flies agent $agent" >&2
  exit 1
fi
network=$($engine inspect "$container" --format '{{range $k, $v := .NetworkSettings.Networks}}{{$k}} {{end}}' | awk '{print $1}')
ip=$($engine inspect "$container" --format "{{(index .NetworkSettings.Networks \"$network\").IPAddress}}")
echo "cut: agent $agent ($container, $ip on $network) off the network for $seconds s"
$engine network disconnect "$network" "$container"
# Reconnected however this script ends (Ctrl-C during the window included).
trap '$engine network connect --ip "$ip" "$network" "$container" && echo "cut: agent $agent reconnected at $ip"' EXIT
sleep "$seconds"
