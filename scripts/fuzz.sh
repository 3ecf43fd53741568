#!/usr/bin/env bash
# Runs every libFuzzer target (fuzz/, device/fuzz/) for SECONDS each (default 600) on a copy of its
# committed seed corpus, and prints one line per target: runs, execs/s, edges covered (libFuzzer's
# `cov:`), corpus size. Builds the `fuzz` preset first. A finding stops the script with the target's
# report and the crashing input (crash-*, leak-*, timeout-* in the work directory, which is kept).
#   scripts/fuzz.sh          # 10 minutes a target
#   scripts/fuzz.sh 25       # what CI runs (.ci/run)
# Extra libFuzzer flags can be given in FUZZ_FLAGS (e.g. FUZZ_FLAGS=-jobs=2); FUZZ_TARGETS="a b" runs only
# those targets and builds only them. FUZZ_RUNS=N stops each target after N inputs (SECONDS stays a cap):
# with a fixed -seed that is the same inputs on a fast or a slow machine, where a time limit is not.
# FUZZ_BUILD_DIR=DIR uses the targets of a tree already configured with BALLBAR_FUZZ=ON instead of the
# fuzz preset's build-fuzz/: CI gives build-asan/, whose `asan` preset builds them along with the tests,
# so that CI compiles the project with clang once, not twice.
set -euo pipefail
cd "$(dirname "$0")/.."
seconds=${1:-600}
case $seconds in '' | *[!0-9]*) echo "usage: scripts/fuzz.sh [SECONDS]" >&2; exit 2 ;; esac
runs_flag=
if [ -n "${FUZZ_RUNS:-}" ]; then
  case $FUZZ_RUNS in *[!0-9]*) echo "FUZZ_RUNS must be a number of inputs" >&2; exit 2 ;; esac
  runs_flag=-runs=$FUZZ_RUNS
fi

targets=(fuzz_decoder)
for dir in fuzz/corpus/*/; do targets+=("$(basename "$dir")"); done
if [ -n "${FUZZ_TARGETS:-}" ]; then read -r -a targets <<<"$FUZZ_TARGETS"; fi

build=${FUZZ_BUILD_DIR:-build-fuzz}
if [ -z "${FUZZ_BUILD_DIR:-}" ]; then
  cmake --preset fuzz >/dev/null
elif ! grep -q '^BALLBAR_FUZZ:BOOL=ON' "$build/CMakeCache.txt" 2>/dev/null; then
  echo "FUZZ_BUILD_DIR=$build is not a tree configured with BALLBAR_FUZZ=ON (e.g. cmake --preset asan)" >&2
  exit 2
fi
if [ -n "${FUZZ_TARGETS:-}" ]; then
  cmake --build "$build" -j2 --target "${targets[@]}"
else
  cmake --build "$build" -j2 --target fuzzers
fi
build=$(cd "$build" && pwd)

work=$(mktemp -d "${TMPDIR:-/tmp}/ballbar-fuzz.XXXXXX")
printf '%-22s %10s %9s %7s %7s\n' target runs execs/s edges corpus
status=0
for t in "${targets[@]}"; do
  exe=$build/fuzz/$t
  [ "$t" = fuzz_decoder ] && exe=$build/device/fuzz/fuzz_decoder
  seeds=fuzz/corpus/$t
  [ "$t" = fuzz_decoder ] && seeds=device/fuzz/corpus
  corpus=$work/$t
  mkdir -p "$corpus"
  if [ -d "$seeds" ]; then cp "$seeds"/* "$corpus"/; fi
  log=$work/$t.log
  # -rss_limit_mb: far above any parser's needs; -max_len: inputs up to 64 KiB (files, programs).
  if ! (cd "$work" && "$exe" -max_total_time="$seconds" -max_len=65536 -rss_limit_mb=2048 \
        -print_final_stats=1 $runs_flag ${FUZZ_FLAGS:-} "$corpus" >"$log" 2>&1); then
    echo "$t: FOUND A PROBLEM (log: $log)" >&2
    tail -n 40 "$log" >&2
    status=1
    continue
  fi
  runs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log" | tail -n 1)
  rate=$(sed -n 's/^stat::average_exec_per_sec: *//p' "$log" | tail -n 1)
  edges=$(grep -o 'cov: [0-9]*' "$log" | tail -n 1 | cut -d' ' -f2)
  files=$(find "$corpus" -type f | wc -l)
  printf '%-22s %10s %9s %7s %7s\n' "$t" "${runs:-?}" "${rate:-?}" "${edges:-?}" "$files"
done
if [ $status -eq 0 ]; then rm -rf "$work"; else echo "work directory kept: $work" >&2; fi
exit $status
