#!/usr/bin/env bash
# Installs what the project needs from Debian 12's archive and configures + builds it.
# Usage: tools/setup.sh [build-dir]     (idempotent; skips apt when everything is present)
# Environment: QSWARM_EXTRA_PACKAGES (more Debian packages, e.g. CI's linters),
#              QSWARM_WERROR=ON (warnings are errors, as in CI),
#              QSWARM_BUILD_TYPE (default RelWithDebInfo; CI builds and tests Release).
set -euo pipefail
cd "$(dirname "$0")/.."
BUILD_DIR="${1:-build}"

PACKAGES=(cmake g++ ninja-build pkg-config git
  libeigen3-dev libgtest-dev libgmock-dev libbenchmark-dev
  libfastrtps-dev libfastcdr-dev fastddsgen fastdds-tools
  libprotobuf-dev protobuf-compiler libspdlog-dev libcli11-dev zlib1g-dev libboost-dev
  python3 python3-matplotlib python3-numpy
  openssl libssl-dev iproute2 iptables procps)
# shellcheck disable=SC2206
PACKAGES+=(${QSWARM_EXTRA_PACKAGES:-})

missing=()
for p in "${PACKAGES[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if ((${#missing[@]})); then
  echo "setup: installing ${missing[*]}"
  SUDO=""
  if [[ $(id -u) -ne 0 ]]; then SUDO="sudo"; fi
  $SUDO apt-get update -q
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -q --no-install-recommends "${missing[@]}"
fi

# npm packages (node/package.json, pinned by node/package-lock.json) go into node/node_modules,
# never committed: the live view's page libraries (three, uplot), which the view server serves, and
# the tests' clients (Foxglove's MCAP reader and WebSocket client, protobufjs, puppeteer-core).
# Installed when missing or older than the lockfile. Node and npm come from Debian (nodejs, npm) when the machine has neither.
if [[ ! -d node/node_modules || node/package-lock.json -nt node/node_modules ]]; then
  if ! command -v npm > /dev/null; then
    SUDO=""
    if [[ $(id -u) -ne 0 ]]; then SUDO="sudo"; fi
    $SUDO apt-get update -q
    DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -q --no-install-recommends nodejs npm
  fi
  echo "setup: npm ci --prefix node"
  npm ci --prefix node --no-audit --no-fund
  touch node/node_modules
fi

# Tests and benchmarks on explicitly: a build directory configured earlier with them off (the
# Release product build CI used to make in build-release/) keeps that in its cache otherwise.
cmake -S . -B "$BUILD_DIR" -G Ninja -DCMAKE_BUILD_TYPE="${QSWARM_BUILD_TYPE:-RelWithDebInfo}" \
  -DQSWARM_WERROR="${QSWARM_WERROR:-OFF}" -DQSWARM_BUILD_TESTS=ON -DQSWARM_BUILD_BENCH=ON
cmake --build "$BUILD_DIR" --parallel "$(nproc)"
