#!/usr/bin/env bash
# Fuzz one target (or all) with libFuzzer in the sanitizer build.
#
#   scripts/fuzz.sh TARGET [SECONDS]     e.g. scripts/fuzz.sh read_ply 600
#   scripts/fuzz.sh all [SECONDS]        every target, two at a time (scripts/test.sh: 10 s each)
#   scripts/fuzz.sh list                 the targets
#
# TARGET is one of tests/fuzz/fuzz_<TARGET>.cpp. Builds build-asan/ first if needed (through
# scripts/sanitize.sh's configuration: PM_FUZZ_SECONDS=0, no suites). The corpus grows in
# build-asan/fuzz-corpus/TARGET (seeded from the generated seeds, the shared data and every
# past finding); a finding is written to build-asan/fuzz-findings/TARGET/ and the run fails.
# PM_FUZZ_SEED: libFuzzer's random seed (default 0: a new one each run; scripts/sanitize.sh
# fixes it at 1, so that CI's short run explores the same inputs for the same code and a red
# run is a change's doing, not luck; longer runs here go further).
# Make every finding a regression test: fix it, then
#   cp build-asan/fuzz-findings/TARGET/crash-... tests/data/fuzz_regressions/TARGET/
# (ctest replays that folder through the target in every build: fuzz.regressions.TARGET).
set -euo pipefail

ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
BUILD="${PM_ASAN_BUILD_DIR:-$ROOT/build-asan}"
TARGET="${1:-list}"
SECONDS_PER_TARGET="${2:-60}"

export ASAN_OPTIONS="${ASAN_OPTIONS:-detect_leaks=1:abort_on_error=0}"
export UBSAN_OPTIONS="${UBSAN_OPTIONS:-halt_on_error=1:print_stacktrace=1}"
export LSAN_OPTIONS="suppressions=$ROOT/tests/lsan.supp${LSAN_OPTIONS:+:$LSAN_OPTIONS}"

if [ ! -f "$BUILD/build.ninja" ]; then
  PM_FUZZ_SECONDS=0 PM_SKIP_SUITES=1 "$ROOT/scripts/sanitize.sh"
fi
targets=$(cd "$BUILD/tests/fuzz" && ls pm_fuzz_* 2>/dev/null | grep -v seeds | sed 's/^pm_fuzz_//' | sort)
if [ "$TARGET" = list ]; then
  echo "$targets"
  exit 0
fi
ninja -C "$BUILD" -j "${PM_JOBS:-$(nproc)}" pm_fuzz_seeds $(for t in $targets; do echo pm_fuzz_$t; done) >/dev/null
SEEDS="$BUILD/tests/fuzz/seeds"
"$BUILD/tests/fuzz/pm_fuzz_seeds" "$SEEDS" "${PM_SHARED_DATA_DIR:-$ROOT/../shared/data}" >/dev/null


fuzz_one() {
  local t="$1" secs="$2"
  local exe="$BUILD/tests/fuzz/pm_fuzz_$t"
  [ -x "$exe" ] || { echo "fuzz: no target '$t' (scripts/fuzz.sh list)" >&2; return 2; }
  local corpus="$BUILD/fuzz-corpus/$t" findings="$BUILD/fuzz-findings/$t"
  mkdir -p "$corpus" "$findings"
  # File formats: inputs up to 64 kB (the seeds from the shared data are cut there); the C
  # ABI targets read a few hundred bytes at most.
  local max_len=65536
  case "$t" in capi_*) max_len=4096 ;; esac
  local log="$BUILD/fuzz-findings/$t.log"
  # -malloc_limit_mb: an allocation beyond it is a finding (a size taken from the input).
  # -timeout: one input taking longer is a finding (a hang).
  if "$exe" "$corpus" "$SEEDS/$t" "$ROOT/tests/data/fuzz_regressions/$t" \
      -max_total_time="$secs" -max_len="$max_len" -timeout=20 -malloc_limit_mb=1024 -rss_limit_mb=3072 \
      -seed="${PM_FUZZ_SEED:-0}" -artifact_prefix="$findings/" -print_final_stats=1 >"$log" 2>&1; then
    echo "fuzz $t: ${secs} s, $(grep -o 'stat::number_of_executed_units: *[0-9]*' "$log" | grep -o '[0-9]*$') runs, $(ls "$corpus" | wc -l) in corpus, no finding"
  else
    echo "fuzz $t: FINDING (see $log; input in $findings/)" >&2
    tail -40 "$log" >&2
    return 1
  fi
}
export -f fuzz_one
export BUILD SEEDS ROOT

if [ "$TARGET" = all ]; then
  # Two at a time: CI has two cores.
  echo "$targets" | xargs -P "${PM_FUZZ_JOBS:-2}" -I{} bash -c 'fuzz_one "$@"' _ {} "$SECONDS_PER_TARGET"
else
  fuzz_one "$TARGET" "$SECONDS_PER_TARGET"
fi
