#!/bin/sh
# Whole-process benchmark: `ballbar compensate` on a generated 1,000,000-block five-axis program
# (target < 1 s). Usage: run_compensate_1m.sh BALLBAR_EXE [RUNS=5] [BLOCKS=1000000] [--exact]
# Prints each run's wall time and the median.
set -eu
exe=${1:?usage: run_compensate_1m.sh BALLBAR_EXE [RUNS] [BLOCKS] [--exact]}
runs=${2:-5}
blocks=${3:-1000000}
extra=${4:-}
dir=$(mktemp -d /tmp/ballbar-comp-bench-XXXXXX)
trap 'rm -rf "$dir"' EXIT

cat >"$dir/model.json" <<'JSON'
{"format":"ballbar-model/1",
 "machine":{"type":"TTTRR","name":"bench","a_pivot_mm":[0,0,0],"c_offset_mm":[0,0,-100],"tool_ball_mm":[0,0,0]},
 "params":{"Y0A":0.025,"Z0A":-0.018,"B0A":4e-5,"C0A":-3e-5,"X0C":0.035,"Y0C":-0.022,"A0C":5e-5,"B0C":-3.5e-5,
           "EXX":8e-6,"EYY":-6e-6,"C0Y":1e-5,"B0Z":-8e-6,"A0Z":6e-6}}
JSON
awk -v n="$blocks" 'BEGIN {
  pi = 3.141592653589793; print "%"; print "O0001 (bench path)"; print "G90 G21";
  for (i = 0; i < n; i++) {
    s = 2 * pi * i / 1000.0;
    printf "G1 X%.4f Y%.4f Z%.4f A%.4f C%.4f F2000\n", 100*cos(s), 100*sin(s), 50+20*sin(3*s), 30+20*sin(2*s), (i % 3600) / 10.0;
  }
  print "M30"; print "%" }' >"$dir/in.nc"

. "$(dirname "$0")/../timing.sh"
# shellcheck disable=SC2086 # $extra is an optional flag
time_runs "$runs" "$blocks blocks" "$exe" compensate --model "$dir/model.json" --program "$dir/in.nc" \
  --out "$dir/out.nc" $extra
