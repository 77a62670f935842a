#!/usr/bin/env bash
# Sets everything up (apt + build) and runs what CI runs (.ci/run calls this):
#   1. a Release build (what users build) of everything, tests included, with warnings as errors,
#      in build-release/; and a configure of the product alone (tests and benchmarks off), from
#      the sources docker/Dockerfile's build stage copies;
#   2. the core, runtime and view tests under AddressSanitizer + UndefinedBehaviorSanitizer (DDS
#      off), and those of them that run threads under ThreadSanitizer (DDS off);
#   3. clang-format on every source, clang-tidy on the product's sources as unity units
#      (tools/lint.sh; `--all` adds the tests and benchmarks: run it before a change to them lands);
#   4. every test but the `long`, `hosts` and `compose` labels, then the `compose` label alone.
#      `hosts` (root, about 6 minutes) runs on its own: tools/test.sh -L hosts, which keeps a CI
#      run under 50 minutes on two cores.
# With arguments, only step 1's build, then ctest with those arguments (e.g. tools/test.sh -L core).
set -euo pipefail
cd "$(dirname "$0")/.."
# Linters, the container tools the compose test (label compose) runs the swarm with (and
# docker-compose, which the hosts label drives podman through: podman-compose 1.0.3 cannot run
# network_mode: host), and the browser the live view's test (view_browser) drives headless.
export QSWARM_EXTRA_PACKAGES="clang-format clang-tidy clang-tools flake8 podman podman-compose
  docker-compose runc netavark aardvark-dns debootstrap catatonit nftables chromium"
BUILD=build-release
QSWARM_BUILD_TYPE=Release QSWARM_WERROR=ON tools/setup.sh "$BUILD"
# --no-tests=error: a label or build that holds no test fails instead of passing empty.
ctest_args=(--output-on-failure --parallel "$(nproc)" --timeout 600 --no-tests=error)
if (($#)); then
  cd "$BUILD"
  exec ctest "${ctest_args[@]}" "$@"
fi
stage() { printf '\n== %s (%s) ==\n' "$*" "$(date +%T)"; }
# What CI runs, everything it needs installed above: a test that cannot run (no engine, no
# browser, no root, a package missing) fails, naming what is missing, instead of passing as
# skipped (ctest counts exit 77 and GTEST_SKIP as passed). The tests read CI.
export CI="${CI:-true}"

stage "the README's test counts against the registered tests"
# Each label's row of the README's table (| `label` | count | what |) must say how many tests that
# label registers: a test that vanishes (a source left out, a discovery that failed) fails here.
counted=0
while read -r label count; do
  have=$(cd "$BUILD" && ctest -N -L "^$label\$" | sed -n 's/^Total Tests: //p')
  if [[ $have != "$count" ]]; then
    echo "README.md says label $label has $count tests; ctest registers ${have:-none}"
    exit 1
  fi
  counted=$((counted + 1))
done < <(sed -n 's/^| `\([a-z]*\)` | \([0-9][0-9]*\) |.*/\1 \2/p' README.md)
((counted >= 10)) || { echo "README.md: the test counts table was not found ($counted rows)"; exit 1; }

stage "the product configured alone (tests and benchmarks off), from the image's sources"
# Catches a product target that only resolves because the test targets exist; what it compiles
# was compiled with -Werror in step 1. Configured from the paths docker/Dockerfile's build stage
# copies, and only those: the compose test flies the release build's programs on the image's
# runtime stage (tests/compose/image.sh), so this is where a source directory CMake names and the
# Dockerfile forgot shows (the programs' unity compile is what lint's clang-tidy parses; the build
# stage's packages are not checked here).
rm -rf build-product && mkdir -p build-product/src
sed -n '/^FROM .* AS build$/,/^FROM /s/^COPY \([^ ]*\) .*/\1/p' docker/Dockerfile |
  while read -r path; do cp -r --parents "$path" build-product/src/; done
cmake -S build-product/src -B build-product/build -G Ninja -DCMAKE_BUILD_TYPE=Release \
  -DQSWARM_WERROR=ON -DQSWARM_BUILD_TESTS=OFF -DQSWARM_BUILD_BENCH=OFF >/dev/null

# The compose stage's image (a Debian base made with debootstrap, then docker/Dockerfile: mostly
# downloads and package installs, then the release build's programs) is made in the background
# from here on, beside the sanitizer and lint stages, which do not measure time, instead of in the
# compose stage: its downloads wait on the network while the compilers use the cores. The tests
# stage starts only once it is done, and the compose test then finds its layers cached (it makes
# them itself if this failed).
setsid tests/compose/image.sh "$BUILD/bin" >"$BUILD/compose-image.log" 2>&1 &
image_job=$!
trap 'kill -- -"$image_job" 2>/dev/null || true' EXIT

# The sanitizer builds compile unity sources (16 files to a unit): about half the time of a build
# file by file. They are not linted and users never build them; the release build above stays
# file by file, so that a missing include still fails it and clang-tidy sees every file.
unity=(-DCMAKE_UNITY_BUILD=ON -DCMAKE_UNITY_BUILD_BATCH_SIZE=16)

# The sanitizer stages build only the test executables they run (ASan: tests-core, tests-runtime,
# tests-view; TSan: tests-threads). One left out would only leave a placeholder test without
# labels, which `ctest -L` skips without a word: fail instead, naming it.
built_all_but() {
  local unbuilt
  unbuilt=$(cd "$1" && ctest -N | sed -n 's/^ *Test *#[0-9]*: \(.*\)_NOT_BUILT$/\1/p' | sort -u |
    tr '\n' ' ')
  [[ $unbuilt == "${2:-}" ]] ||
    { echo "$1: test executables not built: $unbuilt(expected: ${2:-none})"; return 1; }
}

stage "core, runtime and view tests under ASan+UBSan"
cmake -S . -B build-asan -G Ninja -DCMAKE_BUILD_TYPE=Debug -DQSWARM_WITH_DDS=OFF \
  -DQSWARM_SANITIZE=ON -DQSWARM_WERROR=ON -DQSWARM_BUILD_BENCH=OFF "${unity[@]}" >/dev/null
cmake --build build-asan --parallel "$(nproc)" --target tests-core tests-runtime tests-view
built_all_but build-asan
# The closed-loop quadcopter flights of AvoidanceFlight.* and AvoidanceSwarm.* take minutes each at
# -O0 with the sanitizers (500 Hz RK4 and the controller per quadcopter), and so do the 64-agent
# lattices of FormationSwarm.SixtyFour*; they run in the release suite below. The filter itself
# runs here in SafeVelocity.*, the place filter in Neighbourhood.* and the other formations. The
# three 32-agent runs that take a minute or more here (the liar's, the neighbour delivery's, the
# claimers') run the code the shorter tests run, at a larger size: the release suite runs them. So
# do the two sweeps of the place filter's geometry (80 000 steps of two wandering agents, and every
# border crossing 5 cm apart: half a minute each here), whose code the other Neighbourhood.* run.
thirty_two="Insider\\.EdgeFlowFollowsTheLiar|NeighbourDelivery\\.AThirtyTwo|ClaimRunner\\.ThirtyTwo"
sweeps="Neighbourhood\\.(EveryPairWithinTheReach|TheWorstCaseAcrossCellBorders)"
(cd build-asan && ctest "${ctest_args[@]}" -L "core|runtime|view" \
  -E "^(Avoidance(Flight|Swarm)|FormationSwarm\\.SixtyFour|$thirty_two|$sweeps)")

stage "threaded in-process tests under ThreadSanitizer (DDS off)"
# The code that runs beside other threads without Fast DDS: the fault-injecting bus, the agent
# loop, the supervisor's loop, the claim inbox (tests/runtime/concurrency_test.cpp puts real
# threads on each), the port plan's reservations made at once (runtime_tests), the launcher's
# signal handling, and the live view's server (its asio threads against hostile clients,
# tests/view/view_test.cpp). The other in-process executables (scenario, claim, record, mcap,
# sim) run one thread, where ThreadSanitizer has nothing to find: ASan runs them. Any report
# fails the stage (halt_on_error).
cmake -S . -B build-tsan -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DQSWARM_WITH_DDS=OFF \
  -DQSWARM_TSAN=ON -DQSWARM_WERROR=ON -DQSWARM_BUILD_BENCH=OFF "${unity[@]}" >/dev/null
cmake --build build-tsan --parallel "$(nproc)" --target tests-threads
built_all_but build-tsan "claim_tests core_tests mcap_tests record_tests scenario_tests sim_tests "
(cd build-tsan && TSAN_OPTIONS="halt_on_error=1 second_deadlock_stack=1" \
  ctest "${ctest_args[@]}" -L "runtime|view")

stage "format and clang-tidy"
tools/lint.sh "$BUILD"

stage "tests"
wait "$image_job" || echo "the compose image was not made early (the compose stage tries again):" \
  "$(tail -3 "$BUILD/compose-image.log")"
trap - EXIT
cd "$BUILD"
ctest "${ctest_args[@]}" -LE "long|hosts|compose"

stage "compose swarm in containers"
# Alone: it builds an image and runs containers, which would crowd the timing of the other tests.
ctest "${ctest_args[@]}" -L compose
