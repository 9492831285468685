#!/usr/bin/env bash
# Builds the benchmarks (with the Ceres comparison) and prints the README's speed tables:
# every benchmark repeated (default 5) with random interleaving, so that Facet and its peer
# (Ceres, OpenCV) in one table share the machine's state; medians of CPU time, the spread
# (min-max over the repetitions), and the machine's load before and after.
# Usage: bash scripts/bench.sh [repetitions] [benchmark filter regex]
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$root"
bash scripts/setup.sh
build="${FACET_BUILD_DIR:-$root/build/release}"
reps="${1:-5}"
filter="${2:-.}"
cmake -S "$root" -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Release -DFACET_BUILD_BENCH=ON -DFACET_BENCH_CERES=ON >/dev/null
cmake --build "$build" -j "${FACET_JOBS:-2}" --target facet_bench
out="$build/bench.json"
load_before="$(cut -d' ' -f1-3 /proc/loadavg)"
"$build/tests/bench/facet_bench" --benchmark_repetitions="$reps" --benchmark_enable_random_interleaving=true \
  --benchmark_filter="$filter" --benchmark_format=json --benchmark_out="$out" >/dev/null
load_after="$(cut -d' ' -f1-3 /proc/loadavg)"
python3 scripts/bench_report.py "$out" "$load_before" "$load_after"
