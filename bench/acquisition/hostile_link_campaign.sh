#!/usr/bin/env bash
# Issue 24, item 1: is a point ever stored at a wrong pose on a hostile link?
#
# Runs `ballbar demo` (the emulated instrument behind a pty, the real serial path, SQLite) N times per
# machine type for each link below, and counts the sessions that completed, those that gave up (a
# clear message, exit 1) and those that stored a point whose window holds a sample where the emulated
# machine was not at the point's planned pose and socket (the demo checks every stored point of every
# session against the emulator's truth, finished or not). The target: 0 wrong points on every link;
# at least 3 of 4 sessions complete on the first (the issue's link).
#
#   bench/acquisition/hostile_link_campaign.sh [BALLBAR=build/app/ballbar] [RUNS=100] [JOBS=2]
#
# Prints one line per link and machine type, and the wrong points found (their seeds) on stderr.
set -euo pipefail
ballbar=${1:-build/app/ballbar}
runs=${2:-100}
jobs=${3:-2}
[ -x "$ballbar" ] || { echo "no ballbar at $ballbar (build it, or give its path)" >&2; exit 2; }
ballbar=$(realpath "$ballbar")

links=(
  'issue:{"drop_frame_probability":0.2,"corrupt_byte_probability":0.001,"replay_frame_probability":0.2}'
  'worse:{"drop_frame_probability":0.3,"corrupt_byte_probability":0.003,"replay_frame_probability":0.3}'
)

work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

one() {  # TYPE SEED FAULTS -> "done" | "gave-up" | "wrong"
  local type=$1 seed=$2 faults=$3 dir out rc=0
  dir=$(mktemp -d -p "$work")
  out=$("$ballbar" --db "$dir/s.db" demo --machine "$type" --seed "$seed" --faults "$faults" 2>&1) || rc=$?
  rm -rf "$dir"
  if grep -q "away from their pose" <<<"$out" && ! grep -q "all at their pose" <<<"$out"; then
    echo "wrong $type $seed: $(grep -o 'first: .*' <<<"$out" | head -c 300)" >&2
    echo wrong
  elif [ "$rc" -eq 0 ]; then
    echo done
  else
    echo gave-up
  fi
}
export -f one
export ballbar work

printf '%-6s %-6s %5s %9s %8s %12s\n' link type runs completed gave-up wrong-points
for entry in "${links[@]}"; do
  name=${entry%%:*}
  faults=${entry#*:}
  for type in RRTTT TTTRR RTTTR; do
    results=$(seq 1 "$runs" | xargs -P "$jobs" -I{} bash -c 'one "$0" "$1" "$2"' "$type" {} "$faults")
    printf '%-6s %-6s %5d %9d %8d %12d\n' "$name" "$type" "$runs" \
      "$(grep -c '^done$' <<<"$results" || true)" "$(grep -c '^gave-up$' <<<"$results" || true)" \
      "$(grep -c '^wrong$' <<<"$results" || true)"
  done
done
