#!/usr/bin/env bash
# Sets up, builds and runs every Facet test: the unit suites, the offscreen app suites and,
# when ../shared/data is beside the repo, the real-data suite. With FACET_REQUIRE_REALDATA=1
# (CI) a missing ../shared/data is a failure, not a skip. With FACET_BENCH=1 (CI) the
# benchmarks are built too, with the Ceres comparison, so they cannot rot unnoticed.
#
# FACET_SANITIZE=1 runs the same suites in the checked build (cmake/sanitize.cmake): clang,
# AddressSanitizer with its leak checker and UndefinedBehaviorSanitizer, in build/checked.
# Every process the suites start (the offscreen app included) writes any sanitizer report to
# build/checked/sanitizer/, and one report fails the run even if no test noticed it. When
# tests/fuzz exists the checked build also builds the libFuzzer targets (FACET_BUILD_FUZZ),
# so scripts/fuzz.sh can run them from the same tree.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$root"
if [ "${FACET_SANITIZE:-0}" = "1" ]; then bash scripts/setup.sh --checked; else bash scripts/setup.sh; fi
jobs="${FACET_JOBS:-2}"
shared="$(cd "$root/.." && pwd)/shared/data"

# CPU seconds (user + system) of this shell's finished children and their descendants
# (cutime + cstime of /proc/PID/stat; $$ is this shell even inside $(...)).
children_cpu_s() {
  awk -v tck="$(getconf CLK_TCK)" '{ printf "%d", ($16 + $17) / tck }' "/proc/$$/stat"
}

config_flags=(-DCMAKE_BUILD_TYPE=Release)
if [ "${FACET_SANITIZE:-0}" = "1" ]; then
  build="${FACET_BUILD_DIR:-$root/build/checked}"
  cxx="${FACET_SANITIZE_CXX:-clang++-14}"
  config_flags+=(-DFACET_SANITIZE=ON -DCMAKE_CXX_COMPILER="$cxx")
  if [ -f "$root/tests/fuzz/CMakeLists.txt" ]; then
    config_flags+=(-DFACET_BUILD_FUZZ=ON)
  fi
else
  build="${FACET_BUILD_DIR:-$root/build/release}"
fi
if [ "${FACET_BENCH:-0}" = "1" ]; then
  config_flags+=(-DFACET_BUILD_BENCH=ON -DFACET_BENCH_CERES=ON)
fi

start=$(date +%s)
cpu_start=$(children_cpu_s)
cmake -S "$root" -B "$build" -G Ninja -DFACET_SHARED_DATA="$shared" "${config_flags[@]}" >/dev/null
cmake --build "$build" -j "$jobs"
echo "build: $(( $(date +%s) - start )) s wall, $(( $(children_cpu_s) - cpu_start )) s CPU ($build)"

if [ -d "$shared" ]; then
  echo "real-data suite: $shared found, running it"
else
  if [ "${FACET_REQUIRE_REALDATA:-0}" = "1" ]; then
    echo "real-data suite: $shared NOT FOUND, and FACET_REQUIRE_REALDATA=1 requires it" >&2
    exit 1
  fi
  echo "real-data suite: NOT RUN ($shared not found; a fresh clone has no ../shared)"
fi

if [ "${FACET_SANITIZE:-0}" = "1" ]; then
  reports="$build/sanitizer"
  rm -rf "$reports"
  mkdir -p "$reports"
  # Reports go to files (report.PID) rather than stderr so that one raised in a child process,
  # e.g. the app binary an offscreen suite runs, is seen even when that suite expected the
  # child to fail. halt_on_error / -fno-sanitize-recover: the first report ends the process.
  # intercept_tls_get_addr=0: clang 14's runtime guesses the bounds of a dynamic TLS block
  # (a dlopen'ed library's thread_local, here Mesa's) from a header that glibc >= 2.25 no
  # longer writes; on an unlucky heap layout it records a range like [0x3424, 0x1800004526)
  # and LeakSanitizer's tracer then crashes scanning it ("Tracer caught signal 11", seen in
  # the offscreen app; fixed in LLVM 17, google/sanitizers#1409). Without the interception,
  # those blocks are ordinary malloc chunks reached through the thread's DTV, so leak
  # checking loses nothing.
  export ASAN_OPTIONS="detect_leaks=1:halt_on_error=1:check_initialization_order=1:strict_init_order=1:intercept_tls_get_addr=0:log_path=$reports/report"
  export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1:log_path=$reports/report"
  export LSAN_OPTIONS="suppressions=$root/scripts/lsan-suppressions.txt:print_suppressions=0"
  symbolizer="$(command -v llvm-symbolizer-14 || command -v llvm-symbolizer || true)"
  [ -n "$symbolizer" ] && export ASAN_SYMBOLIZER_PATH="$symbolizer"
fi

start=$(date +%s)
cpu_start=$(children_cpu_s)
status=0
# Offscreen app tests render through EGL without a display.
env -u DISPLAY -u WAYLAND_DISPLAY ctest --test-dir "$build" --output-on-failure -j "$jobs" || status=$?
echo "tests: $(( $(date +%s) - start )) s wall, $(( $(children_cpu_s) - cpu_start )) s CPU"

if [ "${FACET_SANITIZE:-0}" = "1" ]; then
  shopt -s nullglob
  found=("$reports"/report.*)
  if [ ${#found[@]} -gt 0 ]; then
    for f in "${found[@]}"; do
      echo "=== sanitizer report $(basename "$f") ==="
      cat "$f"
    done
    echo "sanitizers: ${#found[@]} report(s), the checked run FAILS" >&2
    status=1
  else
    echo "sanitizers: no report (AddressSanitizer, LeakSanitizer, UndefinedBehaviorSanitizer)"
  fi
fi
exit "$status"
