#!/usr/bin/env bash
# Builds the libFuzzer targets (tests/fuzz, clang with ASan + UBSan) and runs each for a while.
#
#   bash scripts/fuzz.sh [SECONDS_PER_TARGET] [TARGET...]     (default 60 s, every target)
#
# Build tree: build/fuzz, or $FACET_BUILD_DIR; with FACET_FUZZ_REUSE_BUILD=1 that tree is used as it
# is configured (the checked build's, which has the targets), else it is configured here. Each target runs on a scratch copy of its seed
# corpus (tests/fuzz/corpus/<target>/), so new inputs never land in the repo; two targets run
# at a time ($FACET_FUZZ_PARALLEL, default 2, one per core). Prints per target the executions,
# exec/s, the coverage before and after and the inputs added; exits non-zero on any crash, leak,
# timeout or out-of-memory, with the reproducer's path and the command that replays it. The
# scratch folder is removed after a clean run, kept after a failure ($FACET_FUZZ_KEEP=1 keeps it
# always).
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$root"
bash scripts/setup.sh --checked

seconds="${1:-60}"
[ $# -gt 0 ] && shift
all_targets=(fuzz_project fuzz_recovery fuzz_colmap_model fuzz_reference fuzz_calibrate_lines fuzz_calibrate_points fuzz_relate_matches fuzz_input_script fuzz_image)
targets=("$@")
[ ${#targets[@]} -eq 0 ] && targets=("${all_targets[@]}")
build="${FACET_BUILD_DIR:-$root/build/fuzz}"
jobs="${FACET_JOBS:-2}"
parallel="${FACET_FUZZ_PARALLEL:-2}"

# The largest input each target may make: a few times its largest seed, well inside the
# parsers' own limits (kMaxTextFileBytes, kMaxImagePixels), and small enough for thousands
# of executions a second.
max_len_of() {
  case "$1" in
    fuzz_project | fuzz_recovery) echo 65536 ;;
    fuzz_image) echo 65536 ;;
    fuzz_input_script) echo 16384 ;;  # the Leuven tutorial seed is 6.6 KiB
    *) echo 16384 ;;
  esac
}

cxx=""
for c in clang++-14 clang++; do
  if command -v "$c" >/dev/null; then cxx="$(command -v "$c")"; break; fi
done
[ -n "$cxx" ] || { echo "fuzz: clang++ not found (scripts/deps-debian.txt lists clang-14)" >&2; exit 1; }
launcher=()
command -v ccache >/dev/null && launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache)

start=$(date +%s)
# -O1 -gline-tables-only (as OSS-Fuzz builds): about half the compile time of -O2 -g under the
# sanitizers, and stacks still name lines. No NDEBUG: an assert reached from input is a finding.
if [ "${FACET_FUZZ_REUSE_BUILD:-0}" = 1 ]; then
  # The checked build's tree (scripts/test.sh with FACET_SANITIZE=1 configures it with
  # FACET_BUILD_FUZZ=ON): build the targets there as it is configured.
  grep -q '^FACET_BUILD_FUZZ:BOOL=ON' "$build/CMakeCache.txt" 2>/dev/null ||
    { echo "fuzz: FACET_FUZZ_REUSE_BUILD=1 but $build is not configured with FACET_BUILD_FUZZ=ON" >&2; exit 1; }
else
  cmake -S "$root" -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -gline-tables-only" \
    -DCMAKE_CXX_COMPILER="$cxx" \
    "${launcher[@]}" -DFACET_BUILD_APP=OFF -DFACET_BUILD_TESTS=OFF -DFACET_BUILD_FUZZ=ON >/dev/null
fi
cmake --build "$build" -j "$jobs" --target "${targets[@]}"
echo "fuzz build: $(($(date +%s) - start)) s"

symbolizer=""
for s in /usr/lib/llvm-14/bin/llvm-symbolizer llvm-symbolizer-14 llvm-symbolizer; do
  if command -v "$s" >/dev/null; then symbolizer="$(command -v "$s")"; break; fi
done
export ASAN_OPTIONS="${ASAN_OPTIONS:-detect_leaks=1:abort_on_error=1:symbolize=1}"
export UBSAN_OPTIONS="${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}"
[ -n "$symbolizer" ] && export ASAN_SYMBOLIZER_PATH="$symbolizer"

scratch="$(mktemp -d "${TMPDIR:-/tmp}/facet-fuzz.XXXXXX")"
run_target() {
  local t="$1" dir="$scratch/$1"
  mkdir -p "$dir/corpus" "$dir/artifacts"
  cp -r "$root/tests/fuzz/corpus/$t/." "$dir/corpus/"
  local dict=()
  [ -f "$root/tests/fuzz/$t.dict" ] && dict=(-dict="$root/tests/fuzz/$t.dict")
  # -timeout: one input taking 20 s (ASan, a loaded machine) is a hang; -rss_limit_mb also
  # bounds any single allocation (malloc_limit_mb defaults to it).
  set +e
  "$build/tests/fuzz/$t" -max_total_time="$seconds" -timeout=20 -rss_limit_mb=2048 -max_len="$(max_len_of "$t")" \
    -print_final_stats=1 -artifact_prefix="$dir/artifacts/" "${dict[@]}" "$dir/corpus" >"$dir/log" 2>&1
  echo $? >"$dir/rc"
  set -e
}

pids=()
for t in "${targets[@]}"; do
  [ -d "$root/tests/fuzz/corpus/$t" ] || { echo "fuzz: no corpus tests/fuzz/corpus/$t" >&2; exit 1; }
  run_target "$t" &
  pids+=($!)
  if [ ${#pids[@]} -ge "$parallel" ]; then
    wait "${pids[0]}"
    pids=("${pids[@]:1}")
  fi
done
wait

failed=0
printf '%-24s %12s %9s %16s %10s %s\n' target executions exec/s "coverage" "new inputs" result
for t in "${targets[@]}"; do
  dir="$scratch/$t"
  log="$dir/log"
  rc="$(cat "$dir/rc")"
  execs="$(sed -n 's/^stat::number_of_executed_units: *//p' "$log" | tail -1)"
  rate="$(sed -n 's/^stat::average_exec_per_sec: *//p' "$log" | tail -1)"
  added="$(sed -n 's/^stat::new_units_added: *//p' "$log" | tail -1)"
  cov_start="$(grep -E '^#[0-9]+[[:space:]]+INITED' "$log" | sed -n 's/.* cov: \([0-9]*\).*/\1/p' | head -1)"
  cov_end="$(grep -oE ' cov: [0-9]+' "$log" | tail -1 | tr -dc 0-9)"
  artifacts="$(find "$dir/artifacts" -type f | sort)"
  result=ok
  if [ "$rc" != 0 ] || [ -n "$artifacts" ]; then
    result="FAILED (exit $rc)"
    failed=1
  fi
  printf '%-24s %12s %9s %16s %10s %s\n' "$t" "${execs:-?}" "${rate:-?}" "${cov_start:-?} -> ${cov_end:-?}" \
    "${added:-?}" "$result"
  if [ "$result" != ok ]; then
    grep -E 'ERROR: (AddressSanitizer|LeakSanitizer|libFuzzer)|runtime error:|Assertion .* failed|property failed|SUMMARY:' "$log" | head -5 |
      sed 's/^/    /'
    for a in $artifacts; do
      echo "    reproducer: $a"
      echo "    replay:     $build/tests/fuzz/$t $a"
    done
    echo "    log:        $log"
  fi
done
if [ "$failed" = 1 ]; then
  echo "fuzz: FAILED; reproducers, logs and corpora are kept in $scratch" >&2
  exit 1
fi
if [ "${FACET_FUZZ_KEEP:-0}" = 1 ]; then
  echo "fuzz: corpora and logs kept in $scratch"
else
  rm -rf "$scratch"
fi
echo "fuzz: ${#targets[@]} targets, ${seconds} s each, no crash, leak or timeout"
