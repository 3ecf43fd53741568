#!/bin/sh
# Whole-process benchmark: `ballbar compensate` on a generated program that is all arcs (G3, 30° each,
# radius 10 mm, A and C moving), linearised at the default chord tolerance (19 chords per arc). Target:
# at most 3x the per-output-block cost of the 1,000,000-block line program (run_compensate_1m.sh).
# Usage: run_compensate_arcs.sh BALLBAR_EXE [RUNS=5] [ARCS=50000]
# Prints each run's wall time, the median, the output blocks and the median per output block.
set -eu
exe=${1:?usage: run_compensate_arcs.sh BALLBAR_EXE [RUNS] [ARCS]}
runs=${2:-5}
arcs=${3:-50000}
dir=$(mktemp -d /tmp/ballbar-comp-arcs-XXXXXX)
trap 'rm -rf "$dir"' EXIT

cat >"$dir/model.json" <<'JSON'
{"format":"ballbar-model/1",
 "machine":{"type":"TTTRR","name":"bench","a_pivot_mm":[0,0,0],"c_offset_mm":[0,0,-100],"tool_ball_mm":[0,0,0]},
 "params":{"Y0A":0.025,"Z0A":-0.018,"B0A":4e-5,"C0A":-3e-5,"X0C":0.035,"Y0C":-0.022,"A0C":5e-5,"B0C":-3.5e-5,
           "EXX":8e-6,"EYY":-6e-6,"C0Y":1e-5,"B0Z":-8e-6,"A0Z":6e-6}}
JSON
awk -v n="$arcs" 'BEGIN {
  pi = 3.141592653589793; print "%"; print "O0002 (bench arcs)"; print "G90 G21 G17";
  printf "G0 X10.0000 Y0.0000 Z50.0000 A30.0000 C0.0000\n";
  xs = 10; ys = 0;
  for (i = 0; i < n; i++) {
    t = (i + 1) * pi / 6;
    xe = 10 * cos(t); ye = 10 * sin(t);
    printf "G3 X%.4f Y%.4f Z%.4f I%.4f J%.4f A%.4f C%.4f F2000\n", xe, ye, 50 + 10 * sin(i / 50.0), -xs, -ys,
           30 + 20 * sin(i / 100.0), (i % 360);
    xs = sprintf("%.4f", xe) + 0; ys = sprintf("%.4f", ye) + 0;
  }
  print "M30"; print "%" }' >"$dir/in.nc"

. "$(dirname "$0")/../timing.sh"
TIME_RUNS_OUT="$dir/summary.json"
result=$(time_runs "$runs" "$arcs arcs" "$exe" compensate --model "$dir/model.json" --program "$dir/in.nc" \
  --out "$dir/out.nc" --json)
echo "$result"
points=$(sed -n 's/.*"points": \([0-9]*\).*/\1/p' "$dir/summary.json")
median=$(echo "$result" | sed -n 's/^median: \([0-9.]*\) s.*/\1/p')
echo "output blocks: $points; per output block: $(echo "$median * 1000000000 / $points" | bc) ns"
