#!/usr/bin/env bash
# Sets everything up (apt + build) and runs what CI runs (.ci/run calls this):
#   1. the default configuration with warnings as errors;
#   2. a Release build of the product with -Werror (what users build, compiled strictly);
#   3. the core and runtime tests under AddressSanitizer + UndefinedBehaviorSanitizer (DDS off);
#   4. clang-format and clang-tidy on the project's own code (tools/lint.sh);
#   5. every test but the `long` and `compose` labels, then the `compose` label alone.
# With arguments, only step 1's build, then ctest with those arguments (e.g. tools/test.sh -L core).
set -euo pipefail
cd "$(dirname "$0")/.."
# Linters, and the container tools the compose test (label compose) runs the swarm with.
export QSWARM_EXTRA_PACKAGES="clang-format clang-tidy clang-tools
  podman podman-compose runc netavark aardvark-dns debootstrap"
QSWARM_WERROR=ON tools/setup.sh build
ctest_args=(--output-on-failure --parallel "$(nproc)" --timeout 600)
if (($#)); then
  cd build
  exec ctest "${ctest_args[@]}" "$@"
fi
stage() { printf '\n== %s (%s) ==\n' "$*" "$(date +%T)"; }

stage "release build with -Werror"
# (The tests and benchmarks were compiled with -Werror in step 1; this is the product.)
cmake -S . -B build-release -G Ninja -DCMAKE_BUILD_TYPE=Release -DQSWARM_WERROR=ON \
  -DQSWARM_BUILD_TESTS=OFF -DQSWARM_BUILD_BENCH=OFF >/dev/null
cmake --build build-release --parallel "$(nproc)"

stage "core and runtime tests under ASan+UBSan"
cmake -S . -B build-asan -G Ninja -DCMAKE_BUILD_TYPE=Debug -DQSWARM_WITH_DDS=OFF \
  -DQSWARM_SANITIZE=ON -DQSWARM_WERROR=ON -DQSWARM_BUILD_BENCH=OFF >/dev/null
cmake --build build-asan --parallel "$(nproc)"
# The closed-loop quadcopter flights of AvoidanceFlight.* and AvoidanceSwarm.* take minutes each at
# -O0 with the sanitizers (500 Hz RK4 and the controller per quadcopter); they run in the release
# suite below. The filter itself runs here in SafeVelocity.*.
(cd build-asan && ctest "${ctest_args[@]}" -L "core|runtime" -E "^Avoidance(Flight|Swarm)\\.")

stage "format and clang-tidy"
tools/lint.sh build

stage "tests"
cd build
ctest "${ctest_args[@]}" -LE "long|compose"

stage "compose swarm in containers"
# Alone: it builds an image and runs containers, which would crowd the timing of the other tests.
ctest "${ctest_args[@]}" -L compose
