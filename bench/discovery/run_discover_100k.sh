#!/bin/sh
# Whole-process discovery: `ballbar discover FILE --json` on 100,800 readings of a TTTRR session written
# by the independent generator (bench_discovery_campaign --write-readings: a once-per-revolution C
# angular error of 80 µrad, outside the library, next to a scale error of X, inside it; 0.3 µm noise
# with n/std_mm), into a fresh database each run: reading the file, importing it as a session, the
# workflow with the search beyond the library (harmonics included) and the learned term, storing the
# result and the extended model.
# Usage: run_discover_100k.sh BALLBAR_EXE BENCH_DISCOVERY_CAMPAIGN_EXE [RUNS=5] [ROWS=100800]
set -eu
exe=${1:?usage: run_discover_100k.sh BALLBAR_EXE BENCH_DISCOVERY_CAMPAIGN_EXE [RUNS] [ROWS]}
gen=${2:?usage: run_discover_100k.sh BALLBAR_EXE BENCH_DISCOVERY_CAMPAIGN_EXE [RUNS] [ROWS]}
runs=${3:-5}
rows=${4:-100800}
dir=$(mktemp -d /tmp/ballbar-disc-bench-XXXXXX)
trap 'rm -rf "$dir"' EXIT
"$gen" --write-readings "$dir/readings.csv" "$rows"
echo "readings: $(($(grep -cv '^#' "$dir/readings.csv") - 1)) rows"
. "$(dirname "$0")/../timing.sh"
before_run() { rm -f "$dir/db.sqlite" "$dir/db.sqlite-wal" "$dir/db.sqlite-shm" "$dir/db.sqlite.lock"; }
TIME_RUNS_OUT="$dir/out.json" time_runs "$runs" "$rows readings" \
  "$exe" --db "$dir/db.sqlite" discover "$dir/readings.csv" --json
echo "named: $(grep -o '"effect": *"[A-Za-z_]*"' "$dir/out.json" | tr '\n' ' ')"
echo "where: $(grep -o '"where": *"[^"]*"' "$dir/out.json" | tr '\n' ' ')"
echo "noise floor: $(grep -o '"noise_floor_um": *[0-9.e-]*' "$dir/out.json"); final: $(grep -o '"rms_final_um": *[0-9.e-]*' "$dir/out.json")"
