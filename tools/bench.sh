#!/usr/bin/env bash
# Core benchmarks (Google Benchmark): medians of 5 repetitions.
set -euo pipefail
cd "$(dirname "$0")/.."
tools/setup.sh build >/dev/null
./build/bench/core_bench --benchmark_repetitions=5 --benchmark_report_aggregates_only=true \
  --benchmark_min_time=0.2 "$@"
