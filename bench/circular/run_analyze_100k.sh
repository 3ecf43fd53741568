#!/bin/sh
# Whole-process circular analysis: `ballbar circle analyze FILE --json` on a 100,000-sample
# ballbar-trace/1 file from the independent generator (XY, R 100 mm, 1000 mm/min, both runs, about
# half of the effects present): reading the file, finding the feed-ins, G, G(b), F and the diagnosis.
# Prints each run's wall time and the median, and the CPU time (user + sys) of each run.
# Usage: run_analyze_100k.sh BALLBAR_EXE MAKE_CIRCULAR_TRACE_EXE [RUNS=7]
set -eu
exe=${1:?usage: run_analyze_100k.sh BALLBAR_EXE MAKE_CIRCULAR_TRACE_EXE [RUNS]}
gen=${2:?usage: run_analyze_100k.sh BALLBAR_EXE MAKE_CIRCULAR_TRACE_EXE [RUNS]}
runs=${3:-7}
dir=$(mktemp -d /tmp/ballbar-circle-bench-XXXXXX)
trap 'rm -rf "$dir"' EXIT
"$gen" "$dir/trace.csv" --samples 100000 --seed 7
. "$(dirname "$0")/../timing.sh"
TIME_RUNS_OUT="$dir/out.json" time_runs "$runs" "100,000 samples" "$exe" --db "$dir/db.sqlite" circle analyze "$dir/trace.csv" --json
if [ -x /usr/bin/time ]; then
  i=0
  while [ "$i" -lt "$runs" ]; do
    /usr/bin/time -f "cpu: %U s user + %S s sys" "$exe" --db "$dir/db.sqlite" circle analyze "$dir/trace.csv" --json >/dev/null
    i=$((i + 1))
  done
fi
echo "G: $(grep -o '"circularity_um": *[0-9.]*' "$dir/out.json" | tr '\n' ' ')"
