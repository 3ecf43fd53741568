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
times=""
i=0
while [ "$i" -lt "$runs" ]; do
  rm -f "$dir/db.sqlite" "$dir/db.sqlite-wal" "$dir/db.sqlite-shm"
  t0=$(date +%s.%N)
  "$exe" --db "$dir/db.sqlite" discover "$dir/readings.csv" --json >"$dir/out.json"
  t1=$(date +%s.%N)
  t=$(echo "$t1 - $t0" | bc)
  echo "run $((i + 1)): ${t} s"
  times="$times $t"
  i=$((i + 1))
done
grep -o '"effect": *"[a-z_XYZ]*"' "$dir/out.json" | head -3
echo "$times" | tr ' ' '\n' | grep -v '^$' | sort -n | awk '{ a[NR] = $1 } END {
  m = (NR % 2) ? a[(NR + 1) / 2] : (a[NR / 2] + a[NR / 2 + 1]) / 2; printf "median: %.3f s\n", m }'
