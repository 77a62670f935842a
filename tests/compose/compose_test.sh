#!/usr/bin/env bash
# ctest label `compose`: the compose swarm for real. Builds the image, flies 6 agent containers
# (ids claimed over DDS, discovery through the Discovery Server, on an internal network), cuts
# one agent's container off the network for a window while the scenario also cuts link 1-2, and
# checks the record on the host: converged, every agent present, the agreed point the initial
# average (relative error < 1e-9, edge-flow), the container cut in events.csv and graph.csv, and a
# replica given an id another one flies refused. The live view (docker/view.yml) is on for that
# run: from the host's loopback, through the relay, the page and its libraries load and npm's
# Foxglove client decodes samples of all N agents (view_check.mjs). Then the secure compose swarm
# (docker-compose.secure.yml, a keystore from `swarm keys --compose`): 6 replicas sharing the
# member identity converge, and a container without it on the same network, flying agent 3 of the
# same scenario, moves nothing. Cleans up its containers and networks.
#
# Usage: compose_test.sh [BIN_DIR] (where `swarm` is; default build/bin). Exit 77 (ctest: skipped)
# with the reason when there is no container engine or no way to make the Debian base image; under
# CI (CI set) exit 1 instead: CI must fly it.
# Environment: QSWARM_COMPOSE_AGENTS (default 6).
set -euo pipefail
SRC="$(cd "$(dirname "$0")/../.." && pwd)"
BIN="${1:-$SRC/build/bin}"
N="${QSWARM_COMPOSE_AGENTS:-6}"
CUT_AGENT=3
skip() {
  if [[ -n ${CI:-} ]]; then echo "FAIL (CI): $*"; exit 1; fi
  echo "SKIPPED: $*"; exit 77
}

command -v podman-compose >/dev/null || skip "no podman-compose"
# Podman works here (else 77), and the base image and the project's image are made (a layer-cache
# hit when tools/test.sh made them earlier), with this build's programs when it has them.
# (Not a sanitizer build's: the image has no sanitizer runtime.)
programs=""
if [[ -x $BIN/swarm-agent && -x $BIN/swarm-supervisor && -x $BIN/swarm-discovery ]] &&
  ! ldd "$BIN/swarm-agent" | grep -qE 'lib(a|t|ub)san'; then
  programs="$BIN"
fi
"$SRC/tests/compose/image.sh" "$programs" || exit $?
export CONTAINERS_CONF="$SRC/tests/compose/containers.conf"
RUNTIME=()
if command -v runc >/dev/null; then RUNTIME=(--runtime runc); fi

PROJECT="qswarm-test-$$"
WORK=$(mktemp -d /tmp/qswarm-compose.XXXXXX)
mkdir -p "$WORK/runs"
# A subnet of its own, so that a user's compose swarm (10.89.77.0/24) and this test can coexist.
export QSWARM_AGENTS="$N" QSWARM_RUNS="$WORK/runs" QSWARM_USER="$(id -u):$(id -g)" \
  QSWARM_SUBNET="10.89.$((100 + $$ % 100)).0/24"
# The view on a free port of the host's loopback.
QSWARM_VIEW_PORT=$(/usr/bin/python3 -c 'import socket; s = socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])')
export QSWARM_VIEW_PORT
COMPOSE=(podman-compose -p "$PROJECT" -f "$SRC/docker/docker-compose.yml" -f "$SRC/docker/view.yml")
SECURE="$PROJECT-secure"
SECURE_COMPOSE=(podman-compose -p "$SECURE" -f "$SRC/docker/docker-compose.yml"
                -f "$SRC/docker/docker-compose.secure.yml")
cleanup() {
  "${COMPOSE[@]}" down >/dev/null 2>&1 || true
  podman rm -f "$PROJECT-dup" >/dev/null 2>&1 || true
  podman network rm -f "${PROJECT}_swarm" "${PROJECT}_view" >/dev/null 2>&1 || true
  if [[ -n "${QSWARM_KEYSTORE:-}" ]]; then
    "${SECURE_COMPOSE[@]}" down >/dev/null 2>&1 || true
  fi
  podman rm -f "$SECURE-stranger" >/dev/null 2>&1 || true
  podman network rm -f "${SECURE}_swarm" >/dev/null 2>&1 || true
  rm -rf "$WORK"
}
trap cleanup EXIT

echo "compose test: $N agents, project $PROJECT"
"${COMPOSE[@]}" --podman-run-args="${RUNTIME[*]}" up -d --no-build >"$WORK/up.log" 2>&1 || {
  cat "$WORK/up.log"; echo "FAIL: compose up"; exit 1; }
sup="${PROJECT}_supervisor_1"

# The run directory the supervisor created, once the whole swarm flies (a complete graph).
FULL=$((N * (N - 1) / 2))
run=""
flying() { [[ -s "$run/graph.csv" ]] && awk -F, -v full="$FULL" 'NR > 1 && $3 == full { found = 1 } END { exit !found }' "$run/graph.csv"; }
for _ in $(seq 1 1500); do
  run=$(find "$WORK/runs" -mindepth 1 -maxdepth 1 -type d | head -1)
  if [[ -n "$run" ]] && flying; then break; fi
  if [[ "$(podman inspect -f '{{.State.Running}}' "$sup" 2>/dev/null)" != "true" ]]; then break; fi
  sleep 0.2
done
[[ -n "$run" ]] && flying || {
  podman logs "$sup" 2>&1 | tail -20; echo "FAIL: the swarm never flew complete"; exit 1; }
echo "compose test: recording into $run"

# The live view from the host while it flies, beside the checks below.
QSWARM_NODE_MODULES="$SRC/node/node_modules" node "$SRC/tests/compose/view_check.mjs" \
  "http://127.0.0.1:$QSWARM_VIEW_PORT/" "$N" >"$WORK/view.log" 2>&1 &
view_pid=$!

# A replica given an id that another one flies is refused (exit 2, a message in its log).
dup_code=0
timeout 300 podman "${RUNTIME[@]}" run --name "$PROJECT-dup" --network "${PROJECT}_swarm" \
  -e QSWARM_AGENTS="$N" localhost/qswarm:latest \
  swarm-agent --scenario /opt/qswarm/scenarios/compose/swarm.txtpb --interface any --id 2 --claim \
  >"$WORK/dup.log" 2>&1 || dup_code=$?

# Cut one agent's container off the network for 6 s, mid-run.
QSWARM_ENGINE=podman "$SRC/docker/cut.sh" "$CUT_AGENT" 6 "$PROJECT"

view_code=0
wait "$view_pid" || view_code=$?
code=$(timeout 600 podman wait "$sup") || { echo "FAIL: the supervisor never ended"; exit 1; }
podman logs "$sup" >"$WORK/supervisor.out" 2>&1 || true
echo "compose test: supervisor exited $code"
cat "$WORK/supervisor.out" | sed -n '/==/,$p'

fail=0
check() { if eval "$2"; then echo "ok: $1"; else echo "FAIL: $1"; fail=1; fi; }
check "a replica given a flown id exits 2 (got $dup_code)" '[[ $dup_code -eq 2 ]]'
check "its log says why" 'grep -q "agent id 2 is already held by another replica" "$WORK/dup.log"'
check "the supervisor exits 0 (converged, complete record)" '[[ $code -eq 0 ]]'
sed 's/^/  view: /' "$WORK/view.log"
check "the live view, from the host through the relay (view_check.mjs exit $view_code)" \
  '[[ $view_code -eq 0 ]]'
sup_nets=$(podman inspect -f '{{range $k, $v := .NetworkSettings.Networks}}{{$k}} {{end}}' "$sup" 2>&1 || true)
check "the supervisor is on the internal network only ($sup_nets)" '[[ $sup_nets == "${PROJECT}_swarm " ]]'
relay_ps=$(podman top "${PROJECT}_view-relay_1" args 2>&1 || true)
check "the relay, the only container with a published port, runs socat and no DDS participant" \
  'grep -q socat <<<"$relay_ps" && ! grep -q swarm- <<<"$relay_ps"'
PYTHONPATH="$SRC/python" /usr/bin/python3 - "$run" "$N" "$CUT_AGENT" <<'PY' || fail=1
import csv, json, os, sys
from qswarm import run_dir as names
run, n, cut = sys.argv[1], int(sys.argv[2]), int(sys.argv[3])
s = json.load(open(os.path.join(run, names.SUMMARY)))
bad = []
def check(name, ok, got):
    print(("ok: " if ok else "FAIL: ") + f"{name} ({got})")
    if not ok: bad.append(name)
check("converged", s.get("converged") is True, s.get("end_reason"))
ids = sorted(a["id"] for a in s.get("agents", []))
check(f"all {n} agents in the summary", ids == list(range(1, n + 1)), ids)
check("no agent missing", not s.get("missing_agents"), s.get("missing_agents"))
err = s.get("average_relative_error", 1.0)
check("agreed value = initial average to < 1e-9", err < 1e-9, err)
events = list(csv.DictReader(open(os.path.join(run, names.EVENTS))))
kinds = [e["kind"] for e in events if e["agent"] == str(cut)]
check(f"agent {cut}'s cut in events.csv (depart, then rejoin)",
      "depart" in kinds and "rejoin" in kinds[kinds.index("depart"):], kinds)
rows = list(csv.DictReader(open(os.path.join(run, names.GRAPH))))
full = n * (n - 1) // 2
edges = [int(r["edges"]) for r in rows]
edges = edges[edges.index(full):] if full in edges else []  # from the first complete graph on
check("graph.csv: the planned cut 1-2 (one edge fewer)", full - 1 in edges, sorted(set(edges)))
check(f"graph.csv: the container cut (agent {cut}'s {n - 1} edges gone)",
      any(e <= full - (n - 1) for e in edges), min(edges, default=None))
check("graph.csv: whole again at the end", edges and edges[-1] == full, edges[-1:])
sys.exit(1 if bad else 0)
PY

# The secure compose swarm: the same scenario, a compose keystore (one member identity that the
# replicas share, and the supervisor's), simple discovery by unicast to the services' addresses;
# a stranger container without the keystore on the same network flies agent 3 of the same
# scenario (the same run id) from the start, and announces itself to the same addresses, as the
# replicas do (a stranger the replicas never hear of would prove nothing). Its own network,
# subnet and record directory.
"$BIN/swarm" keys "$SRC/docker/scenarios/swarm.txtpb" --compose --out "$WORK/keys" >/dev/null || {
  echo "FAIL: swarm keys --compose"; exit 1; }
mkdir -p "$WORK/runs-secure"
export QSWARM_KEYSTORE="$WORK/keys" QSWARM_RUNS="$WORK/runs-secure" QSWARM_DISCOVERY_SERVER=none \
  QSWARM_SUBNET="10.89.$((200 + $$ % 50)).0/24"
echo "compose test: secure, $N agents, project $SECURE"
"${SECURE_COMPOSE[@]}" --podman-run-args="${RUNTIME[*]}" up -d --no-build >"$WORK/up-secure.log" 2>&1 || {
  cat "$WORK/up-secure.log"; echo "FAIL: secure compose up"; exit 1; }
podman "${RUNTIME[@]}" run -d --name "$SECURE-stranger" --network "${SECURE}_swarm" \
  -e QSWARM_AGENTS="$N" -e QSWARM_PEER_HOSTS=agent,supervisor localhost/qswarm:latest \
  swarm-agent --scenario /opt/qswarm/scenarios/compose/swarm.txtpb --interface any --id 3 \
  --start-timeout 5 >/dev/null
ssup="${SECURE}_supervisor_1"
scode=$(timeout 600 podman wait "$ssup") || { echo "FAIL: the secure supervisor never ended"; exit 1; }
podman logs "$ssup" >"$WORK/supervisor-secure.out" 2>&1 || true
podman stop -t 5 "$SECURE-stranger" >/dev/null 2>&1 || true
podman logs "$SECURE-stranger" >"$WORK/stranger.log" 2>&1 || true
echo "compose test: secure supervisor exited $scode"
sed -n '/==/,$p' "$WORK/supervisor-secure.out"
if [[ $scode -ne 0 ]]; then
  # What each replica said: the one place that tells a handshake that never finished from a
  # replica that never claimed its id.
  tail -15 "$WORK/supervisor-secure.out" | sed 's/^/  supervisor: /'
  for c in $(podman ps -a --format '{{.Names}}' | grep "^${SECURE}_agent_" || true); do
    podman logs "$c" 2>&1 | tail -12 | sed "s/^/  $c: /" || true
  done
fi
srun=$(find "$WORK/runs-secure" -mindepth 1 -maxdepth 1 -type d | head -1)
check "secure: the supervisor exits 0 (converged, complete record)" '[[ $scode -eq 0 ]]'
check "secure: the stranger announced itself to the $((N + 1)) peer hosts" \
  'grep -q "peer hosts agent,supervisor: $((N + 1)) addresses" "$WORK/stranger.log"'
check "secure: the stranger heard none of the replicas" \
  'grep -q "start timeout: 0 of" "$WORK/stranger.log"'
# Discovery by unicast to every replica and the supervisor, not by multicast (docs/security.md,
# "Discovery by unicast"): each replica's log says where it found them.
# (grep reads the whole log: with -q it would stop early, and pipefail would see podman's SIGPIPE.)
unicast=0
for c in $(podman ps -a --format '{{.Names}}' | grep "^${SECURE}_agent_" || true); do
  podman logs "$c" 2>&1 | grep "peer hosts agent,supervisor: $((N + 1)) addresses" >/dev/null &&
    unicast=$((unicast + 1))
done
check "secure: every replica discovered by unicast at the $((N + 1)) peer hosts ($unicast of $N)" \
  '[[ $unicast -eq $N ]]'
PYTHONPATH="$SRC/python" /usr/bin/python3 - "$srun" "$N" <<'PY' || fail=1
import csv, json, os, sys
from qswarm import run_dir as names
run, n = sys.argv[1], int(sys.argv[2])
s = json.load(open(os.path.join(run, names.SUMMARY)))
bad = []
def check(name, ok, got):
    print(("ok: " if ok else "FAIL: ") + f"secure: {name} ({got})")
    if not ok: bad.append(name)
check("DDS-Security on", s.get("secure") is True, s.get("secure"))
check("converged", s.get("converged") is True, s.get("end_reason"))
ids = sorted(a["id"] for a in s.get("agents", []))
check(f"all {n} agents in the summary", ids == list(range(1, n + 1)), ids)
err = s.get("average_relative_error", 1.0)
check("agreed value = initial average to < 1e-9 (the stranger moved nothing)", err < 1e-9, err)
check("no forgery named", not s.get("forgeries"), s.get("forgeries"))
events = list(csv.DictReader(open(os.path.join(run, names.EVENTS))))
odd = [e["kind"] for e in events if e["kind"] in ("forgery", "unknown_agent", "foreign_run")]
check("no stranger, forgery or other run in events.csv", not odd, odd)
sys.exit(1 if bad else 0)
PY
exit $fail
