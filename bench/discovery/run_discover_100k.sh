#!/bin/sh
# Whole-process discovery: `ballbar discover FILE --json` on the 100,800-reading TTTRR session of
# bench_discovery (one hidden effect, scale_X), into a fresh database each run: reading the file,
# importing it as a session, the workflow, storing the result and the extended model.
# Usage: run_discover_100k.sh BALLBAR_EXE BENCH_DISCOVERY_EXE [RUNS=5] [REPEAT=400]
set -eu
exe=${1:?usage: run_discover_100k.sh BALLBAR_EXE BENCH_DISCOVERY_EXE [RUNS] [REPEAT]}
gen=${2:?usage: run_discover_100k.sh BALLBAR_EXE BENCH_DISCOVERY_EXE [RUNS] [REPEAT]}
runs=${3:-5}
repeat=${4:-400}
dir=$(mktemp -d /tmp/ballbar-disc-bench-XXXXXX)
trap 'rm -rf "$dir"' EXIT
"$gen" --write-readings "$dir/readings.csv" "$repeat"
echo "readings: $(($(grep -cv '^#' "$dir/readings.csv") - 1)) rows"
. "$(dirname "$0")/../timing.sh"
before_run() { rm -f "$dir/db.sqlite" "$dir/db.sqlite-wal" "$dir/db.sqlite-shm" "$dir/db.sqlite.lock"; }
TIME_RUNS_OUT="$dir/out.json" time_runs "$runs" "$repeat x 252 readings" \
  "$exe" --db "$dir/db.sqlite" discover "$dir/readings.csv" --json
echo "named: $(grep -o '"effect": *"[a-z_XYZ]*"' "$dir/out.json" | tr '\n' ' ')"
