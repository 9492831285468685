#!/usr/bin/env bash
# Sets up, builds and runs every Facet test: the unit suites, the offscreen app suites and,
# when ../shared/data is beside the repo, the real-data suite. With FACET_REQUIRE_REALDATA=1
# (CI) a missing ../shared/data is a failure, not a skip. With FACET_BENCH=1 (CI) the
# benchmarks are built too, with the Ceres comparison, so they cannot rot unnoticed.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$root"
bash scripts/setup.sh
build="${FACET_BUILD_DIR:-$root/build/release}"
jobs="${FACET_JOBS:-2}"
shared="$(cd "$root/.." && pwd)/shared/data"

start=$(date +%s)
bench_flags=()
if [ "${FACET_BENCH:-0}" = "1" ]; then
  bench_flags=(-DFACET_BUILD_BENCH=ON -DFACET_BENCH_CERES=ON)
fi
cmake -S "$root" -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Release -DFACET_SHARED_DATA="$shared" "${bench_flags[@]}" >/dev/null
cmake --build "$build" -j "$jobs"
echo "build: $(( $(date +%s) - start )) s"

if [ -d "$shared" ]; then
  echo "real-data suite: $shared found, running it"
else
  if [ "${FACET_REQUIRE_REALDATA:-0}" = "1" ]; then
    echo "real-data suite: $shared NOT FOUND, and FACET_REQUIRE_REALDATA=1 requires it" >&2
    exit 1
  fi
  echo "real-data suite: NOT RUN ($shared not found; a fresh clone has no ../shared)"
fi

start=$(date +%s)
# Offscreen app tests render through EGL without a display.
env -u DISPLAY -u WAYLAND_DISPLAY ctest --test-dir "$build" --output-on-failure -j "$jobs"
echo "tests: $(( $(date +%s) - start )) s"
