#!/usr/bin/env bash
# Runs a command with a DDS domain this process holds alone on this host, as the C++ tests'
# DomainLease does (tests/swarm/domain_lease.hpp): an exclusive flock on
# /tmp/qswarm-test-domains/D.lock, held by the command (fd 9 is inherited) until it exits.
# Usage: lease_domain.sh KEY COMMAND...   (the command finds the domain in $QSWARM_TEST_DOMAIN)
set -euo pipefail
key="$1"
shift
dir=/tmp/qswarm-test-domains
mkdir -p "$dir"
span=13 first=10  # 10..22: the port plan ends at 22
start=$(($(printf '%s' "$key" | cksum | cut -d' ' -f1) % span))
for k in $(seq 0 $((span - 1))); do
  d=$((first + (start + k) % span))
  exec 9>>"$dir/$d.lock"
  if flock -n 9; then
    export QSWARM_TEST_DOMAIN=$d
    exec "$@"
  fi
  exec 9>&-
done
echo "no free DDS test domain in 10..22" >&2
exit 1
