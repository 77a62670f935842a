#!/usr/bin/env bash
# ctest label `hosts`: what `swarm deploy k8s` writes, flown. podman kube play runs podman.yaml,
# the containers of the Kubernetes manifests as one Pod per process (two Discovery Servers, the
# supervisor, 12 agents, each pod its own address), on an internal network whose bridge forwards
# no IPv4 multicast or broadcast between pods (an nftables rule this test adds and removes), as on
# most cluster networks. Run 1: the 12 converge on the exact initial average, each agent's record
# names its pod. Run 2: once the swarm flies, one agent's pod is removed: the supervisor names it
# missing and exits 1. Run 3: that pod removed and played again at a new address, as a cluster
# restarts a pod on another node: it rejoins under its id, asks back the flows it held, and the
# swarm converges on the exact average. Run 4, secure (`--keystore`): the keystore's files as
# ConfigMaps (podman 4.3 cannot mount the Secrets quadswarm.yaml uses), each pod given only its
# own identity, copied into its keystore by an init container; discovery by unicast at every
# pod's name, no server: the 12 converge on the exact average with DDS-Security on.
#
# Usage: kube_play_test.sh [BIN_DIR]. Exit 77 (skipped) without podman, root or nftables, unless CI
# is set (then 1: CI must fly it).
set -euo pipefail
SRC="$(cd "$(dirname "$0")/../.." && pwd)"
BIN="${1:-$SRC/build/bin}"
N=12
REMOVED=5  # the ordinal of the pod removed in run 2: it flies the scenario's 6th agent
skip() {
  if [[ -n ${CI:-} ]]; then echo "FAIL (CI): $*"; exit 1; fi
  echo "SKIPPED: $*"; exit 77
}
[[ $(id -u) -eq 0 ]] || skip "needs root (a podman network and an nftables rule)"
command -v nft >/dev/null || skip "no nft (apt-get install nftables)"
command -v catatonit >/dev/null || skip "no catatonit, which podman's pods need (apt-get install catatonit)"
programs=""
if [[ -x $BIN/swarm-agent && -x $BIN/swarm-supervisor && -x $BIN/swarm-discovery ]] &&
  ! ldd "$BIN/swarm-agent" | grep -qE 'lib(a|t|ub)san'; then
  programs="$BIN"
fi
code=0
"$SRC/tests/compose/image.sh" "$programs" || code=$?
((code == 77)) && skip "no image (tests/compose/image.sh)"
((code == 0)) || exit "$code"
export CONTAINERS_CONF="$SRC/tests/compose/containers.conf"
RUNTIME=()
if command -v runc >/dev/null; then RUNTIME=(--runtime runc); fi

NAME="qsw$$"
NET="$NAME-net"
SUBNET="10.89.$((150 + $$ % 50)).0/24"
WORK=$(mktemp -d /tmp/qswarm-kube.XXXXXX)
down() {
  [[ -f $1 ]] && podman kube down "$1" >/dev/null 2>&1 || true
  # kube down stops at a pod removed before it (run 2's), and leaves the volumes of the claim and
  # of the ConfigMaps.
  local v
  for v in $(podman pod ls --format '{{.Name}}' | grep "^$NAME-" || true); do
    podman pod rm -f "$v" >/dev/null 2>&1 || true
  done
  for v in $(podman volume ls -q | grep "^$NAME-" || true); do
    podman volume rm -f "$v" >/dev/null 2>&1 || true
  done
}
cleanup() {
  down "$WORK/d1/podman.yaml"
  down "$WORK/d2/podman.yaml"
  down "$WORK/d3/podman.yaml"
  down "$WORK/d4/podman.yaml"
  podman network rm -f "$NET" >/dev/null 2>&1 || true
  nft delete table bridge "$NAME" 2>/dev/null || true
  rm -rf "$WORK"
}
trap cleanup EXIT

podman network create --internal --subnet "$SUBNET" "$NET" >/dev/null
nft -f - <<EOF
table bridge $NAME {
  chain forward {
    type filter hook forward priority 0; policy accept;
    ip saddr $SUBNET meta pkttype { broadcast, multicast } counter drop
  }
}
EOF

sup="$NAME-supervisor-supervisor"
# Writes scenario $1 with gain $2, deploys it into $WORK/$1 (secure, with a keystore made for it,
# if $3 is "secure"), plays it; echoes the record's volume.
play() {
  local size=(--agents "$N") keys=()
  if [[ ${3:-} == secure ]]; then
    echo "random_agents { count: $N box_m: 20 }" >"$WORK/$1.txtpb"
    size=()
  else
    : >"$WORK/$1.txtpb"
  fi
  cat >>"$WORK/$1.txtpb" <<EOF
name: "kube-$1"
gain: $2
weight { policy: UNWEIGHTED }
topology { policy: PROXIMITY threshold_m: 1000 }
convergence { tolerance_m: 1e-6 hold_s: 1 }
duration_s: 60
seed: 3
EOF
  if [[ ${3:-} == secure ]]; then
    "$BIN/swarm" keys "$WORK/$1.txtpb" --out "$WORK/$1.keys" >/dev/null ||
      { echo "FAIL: swarm keys" >&2; exit 1; }
    keys=(--keystore "$WORK/$1.keys")
  fi
  "$BIN/swarm" deploy k8s "$WORK/$1.txtpb" "${size[@]}" "${keys[@]}" --out "$WORK/$1" \
    --name "$NAME" >/dev/null || { echo "FAIL: swarm deploy k8s" >&2; exit 1; }
  # Said on stderr: stdout is the caller's $(...).
  timeout 300 podman "${RUNTIME[@]}" kube play --network "$NET" "$WORK/$1/podman.yaml" \
    >"$WORK/$1.play" 2>&1 || { cat "$WORK/$1.play" >&2; echo "FAIL: kube play ($1)" >&2; exit 1; }
  podman volume inspect "$NAME-runs" --format '{{.Mountpoint}}'
}
# The supervisor's exit code, once it ends (at most 300 s).
verdict() {
  local c
  c=$(timeout 300 podman wait "$sup") || { echo "FAIL: the supervisor never ended"; exit 1; }
  podman logs "$sup" >"$WORK/supervisor.out" 2>&1 || true
  sed -n '/==/,$p' "$WORK/supervisor.out" | head -12 >&2
  echo "$c"
}
record_checks() {
  PYTHONPATH="$SRC/python" /usr/bin/python3 - "$@" <<'PY'
import glob, json, os, sys
from qswarm import run_dir as names
volume, n, name, removed = sys.argv[1], int(sys.argv[2]), sys.argv[3], int(sys.argv[4])
secure = len(sys.argv) > 5
runs = sorted(glob.glob(os.path.join(volume, "*")))
s = json.load(open(os.path.join(runs[-1], names.SUMMARY)))
bad = []
def check(what, ok, got):
    print(("ok: " if ok else "FAIL: ") + f"{what} ({got})")
    if not ok: bad.append(what)
hosts = {a["id"]: a.get("hosts", []) for a in s["agents"]}
if removed < 0:
    check("converged", s.get("converged") is True, s.get("end_reason"))
    check("DDS-Security " + ("on" if secure else "off"), s.get("secure") is secure, s.get("secure"))
    err = s.get("average_relative_error", 1.0)
    check("agreed value = initial average to < 1e-9", err < 1e-9, err)
    check(f"all {n} agents", sorted(hosts) == list(range(1, n + 1)), sorted(hosts))
    # Pod NAME-agent-K flies the K-th agent (id K + 1 here), and its record says so.
    wrong = [i for i, h in hosts.items() if not h or not h[0].startswith(f"{name}-agent-{i - 1}/")]
    check("each agent's recorded host is its own pod", not wrong, {i: hosts[i] for i in wrong})
else:
    check("not converged", s.get("converged") is False, s.get("end_reason"))
    check(f"agent {removed + 1} named missing", removed + 1 in s.get("missing_agents", []),
          s.get("missing_agents"))
sys.exit(1 if bad else 0)
PY
}

echo "kube play test: run 1, $N agent pods, project $NAME, network $NET ($SUBNET)"
vol=$(play d1 1)
code=$(verdict)
fail=0
[[ $code == 0 ]] && echo "ok: the supervisor exits 0" || { echo "FAIL: the supervisor exited $code"; fail=1; }
if ! record_checks "$vol" "$N" "$NAME" -1; then
  fail=1
  # What the agents said about what they dropped or lost, for whoever reads the failure.
  for k in $(seq 0 $((N - 1))); do
    podman logs "$NAME-agent-$k-agent" 2>&1 | grep -iE "drop|refus|warn|lost|stale" | head -3 |
      sed "s/^/  agent pod $k: /"
  done
fi
down "$WORK/d1/podman.yaml"

echo "kube play test: run 2, pod $NAME-agent-$REMOVED removed mid-run"
vol=$(play d2 0.05)
flying() {
  local t
  t=$(find "$vol" -name telemetry.csv -exec awk -F, 'NR > 1 && $4 == 1 && $1 > m { m = $1 } END { print m + 0 }' {} \; 2>/dev/null | head -1)
  awk -v t="${t:-0}" 'BEGIN { exit !(t >= 2) }'
}
for _ in $(seq 1 600); do flying && break; sleep 0.2; done
flying || { podman logs "$sup" 2>&1 | tail; echo "FAIL: run 2 never flew"; exit 1; }
podman pod rm -f "$NAME-agent-$REMOVED" >/dev/null
code=$(verdict)
[[ $code == 1 ]] && echo "ok: the supervisor exits 1" || { echo "FAIL: the supervisor exited $code"; fail=1; }
record_checks "$vol" "$N" "$NAME" "$REMOVED" || fail=1
down "$WORK/d2/podman.yaml"

echo "kube play test: run 3, pod $NAME-agent-$REMOVED restarted at another address mid-run"
vol=$(play d3 0.05)
for _ in $(seq 1 600); do flying && break; sleep 0.2; done
flying || { podman logs "$sup" 2>&1 | tail; echo "FAIL: run 3 never flew"; exit 1; }
# The pod as its controller would make it again: the same spec, a new address, nothing else.
/usr/bin/python3 - "$WORK/d3/podman.yaml" "$NAME-agent-$REMOVED" "$WORK/d3" <<'PY'
import sys
docs = open(sys.argv[1]).read().split("\n---\n")
pod = [d for d in docs if f"name: {sys.argv[2]}\n" in d and "kind: Pod" in d]
scenario = [d for d in docs if "kind: ConfigMap" in d]
open(sys.argv[3] + "/again.yaml", "w").write(pod[0] + "\n")
open(sys.argv[3] + "/scenario.yaml", "w").write(scenario[0].split("\n", 2)[-1] + "\n")
PY
old_ip=$(podman inspect "$NAME-agent-$REMOVED-agent" --format '{{range .NetworkSettings.Networks}}{{.IPAddress}}{{end}}')
podman pod rm -f "$NAME-agent-$REMOVED" >/dev/null
new_ip="${SUBNET%.0/24}.250"
podman "${RUNTIME[@]}" kube play --network "$NET" --ip "$new_ip" --configmap "$WORK/d3/scenario.yaml" \
  "$WORK/d3/again.yaml" >"$WORK/d3.again" 2>&1 || { cat "$WORK/d3.again"; echo "FAIL: replay"; exit 1; }
code=$(verdict)
[[ $code == 0 ]] && echo "ok: the supervisor exits 0" || { echo "FAIL: the supervisor exited $code"; fail=1; }
record_checks "$vol" "$N" "$NAME" -1 || fail=1
PYTHONPATH="$SRC/python" /usr/bin/python3 - "$vol" "$((REMOVED + 1))" "$old_ip" "$new_ip" <<'PY' || fail=1
import glob, json, os, sys
from qswarm import run_dir as names
volume, agent, old, new = sys.argv[1], int(sys.argv[2]), sys.argv[3], sys.argv[4]
s = json.load(open(os.path.join(sorted(glob.glob(os.path.join(volume, "*")))[-1], names.SUMMARY)))
hosts = next(a.get("hosts", []) for a in s["agents"] if a["id"] == agent)
ok = len(hosts) == 2 and hosts[0].endswith("/" + old) and hosts[1].endswith("/" + new)
print(("ok: " if ok else "FAIL: ") + f"agent {agent} flew at {old}, then at {new} ({hosts})")
sys.exit(0 if ok else 1)
PY
down "$WORK/d3/podman.yaml"

echo "kube play test: run 4, secure, $N agent pods"
vol=$(play d4 1 secure)
code=$(verdict)
[[ $code == 0 ]] && echo "ok: the supervisor exits 0" || { echo "FAIL: the supervisor exited $code"; fail=1; }
record_checks "$vol" "$N" "$NAME" -1 secure || fail=1
echo "multicast and broadcast between pods dropped by the bridge: $(nft list table bridge "$NAME" | grep -o 'packets [0-9]*')"
exit "$fail"
