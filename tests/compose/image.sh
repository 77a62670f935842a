#!/usr/bin/env bash
# Makes what the compose swarm runs: the debian:bookworm-slim base (from Debian's packages with
# debootstrap, once: no image registry is reachable) and the project's image from docker/Dockerfile
# (localhost/qswarm:latest, with podman's layer cache). compose_test.sh calls it; tools/test.sh also
# starts it early, beside stages that do not measure time, so that the compose stage finds it made.
# Exit 77 with the reason when it cannot be made here (no podman, no root for debootstrap); under
# CI (CI set) exit 1, so that no test that needs it passes as skipped.
#
# Usage: image.sh [PROGRAMS_DIR]. Given a directory holding swarm-agent, swarm-supervisor and
# swarm-discovery (a release build's bin/), the image is the Dockerfile's runtime-base stage with
# those programs (stripped copies) instead of the ones its build stage would compile: the test
# then flies the build it tests, and CI does not compile them a second time. Without it, the
# whole Dockerfile, as users build it.
set -euo pipefail
SRC="$(cd "$(dirname "$0")/../.." && pwd)"
skip() {
  if [[ -n ${CI:-} ]]; then echo "FAIL (CI): $*"; exit 1; fi
  echo "SKIPPED: $*"; exit 77
}

command -v podman >/dev/null || skip "no podman (apt-get install podman podman-compose runc debootstrap)"
export CONTAINERS_CONF="$SRC/tests/compose/containers.conf"
RUNTIME=()
if command -v runc >/dev/null; then RUNTIME=(--runtime runc); fi
podman "${RUNTIME[@]}" info >/dev/null 2>&1 || skip "podman does not work here: $(podman info 2>&1 | tail -1)"

if ! podman image exists docker.io/library/debian:bookworm-slim; then
  [[ $(id -u) -eq 0 ]] || skip "no debian:bookworm-slim image, and making one needs root (debootstrap)"
  command -v debootstrap >/dev/null || skip "no debian:bookworm-slim image and no debootstrap"
  rootfs=$(mktemp -d /var/tmp/qswarm-rootfs.XXXXXX)
  echo "compose image: making debian:bookworm-slim with debootstrap (about 2 minutes)"
  debootstrap --variant=minbase bookworm "$rootfs" >/dev/null
  tar -C "$rootfs" -c . | podman import - docker.io/library/debian:bookworm-slim >/dev/null
  rm -rf "$rootfs"
fi
PROGRAMS="${1:-}"
if [[ -z $PROGRAMS ]]; then
  echo "compose image: building localhost/qswarm:latest"
  podman "${RUNTIME[@]}" build --pull=never --layers -q -f "$SRC/docker/Dockerfile" \
    -t localhost/qswarm:latest "$SRC" >/dev/null
  exit 0
fi
echo "compose image: building localhost/qswarm:latest with the programs of $PROGRAMS"
# The stages the target does not use (the build stage) are skipped (podman's default).
podman "${RUNTIME[@]}" build --pull=never --layers -q -f "$SRC/docker/Dockerfile" \
  --target runtime-base -t localhost/qswarm-base:latest "$SRC" >/dev/null
stage=$(mktemp -d)
trap 'rm -rf "$stage"' EXIT
for p in swarm-agent swarm-supervisor swarm-discovery; do
  strip -o "$stage/$p" "$PROGRAMS/$p"
done
printf 'FROM localhost/qswarm-base:latest\nCOPY %s /usr/local/bin/\n' \
  "swarm-agent swarm-supervisor swarm-discovery" >"$stage/Containerfile"
podman "${RUNTIME[@]}" build --pull=never --layers -q -f "$stage/Containerfile" \
  -t localhost/qswarm:latest "$stage" >/dev/null
