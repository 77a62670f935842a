#!/usr/bin/env bash
# How far qswarm-attacker (tests/attacker) moves a run, plain and secure: faults_six flown by
# `swarm run` once per attack, the attacker started first on the same domain (docs/security.md,
# "what the same stranger does"). One line per run: the end, the exit code, the drift of the
# final mean from the initial average, what the record named, what the attacker heard and sent.
# Usage: bench/attack_exposure.sh        Environment: BUILD_DIR=build DOMAIN=13 DURATION=30
set -uo pipefail
cd "$(dirname "$0")/.." || exit 2
B=${BUILD_DIR:-build}/bin
S=scenarios/faults_six.txtpb
OUT=${BUILD_DIR:-build}/bench-runs/exposure
D=${DOMAIN:-13}
mkdir -p "$OUT"
[[ -d $OUT/keys ]] || "$B/swarm" keys "$S" --out "$OUT/keys" >/dev/null
one() {  # NAME SECURE(0/1) ATTACKER-ARGS...
  local name=$1 secure=$2
  shift 2
  rm -rf "${OUT:?}/$name" "$OUT/$name.rep"
  "$B/qswarm-attacker" --domain "$D" --report "$OUT/$name.rep" "$@" >"$OUT/$name.att" 2>&1 &
  local attacker=$! extra=()
  [[ $secure == 1 ]] && extra=(--secure "$OUT/keys")
  "$B/swarm" run "$S" --out "$OUT/$name" --domain "$D" --quiet --duration "${DURATION:-30}" \
    "${extra[@]}" >"$OUT/$name.out" 2>&1
  local code=$?
  kill -TERM "$attacker" 2>/dev/null
  wait "$attacker" 2>/dev/null
  /usr/bin/python3 - "$OUT/$name" "$code" "$OUT/$name.rep" <<'PY'
import json, sys
run, code, rep = sys.argv[1:4]
s = json.load(open(run + "/summary.json"))
r = dict(line.strip().split("=", 1) for line in open(rep) if "=" in line)
named = ",".join(sorted({f"{f['agent']}:{f['kind']}" for f in s.get("forgeries", [])})) or "-"
print(f"{run.split('/')[-1]} | {s['end_reason'][:60]} | exit {code} | drift "
      f"{s['average_drift_m']:.3g} m | named {named} | attacker heard {r.get('heard')}, "
      f"published {r.get('published')}, learned {r.get('learned')}")
PY
}
K=(--keystore "$OUT/keys" --identity agent-3)
one relay-plain 0 --mode relay --victim 1 --streams state
one relay4-plain 0 --mode relay --victim 1 --streams state --copies 4
one impersonate8-plain 0 --mode impersonate --victim 3 --rate 200 --for 8
one impersonate-plain 0 --mode impersonate --victim 3 --rate 200
one relay4-secure-stranger 1 --mode relay --victim 1 --copies 4 --learn-timeout 20
one as5-secure-member 1 --mode impersonate --as 5 --rate 200 "${K[@]}"
one as3-secure-member 1 --mode impersonate --victim 3 --rate 200 "${K[@]}"
