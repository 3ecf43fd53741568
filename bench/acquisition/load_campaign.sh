#!/usr/bin/env bash
# Issue 24, item 8: do the demos hold on a busy host?
#
# Starts HOGS busy processes (shell loops, one per core on the 2-core machine: a load of about 2 beside
# the demo) and runs each demo below RUNS times, one after another, each with its own seed and database.
# A real instrument streams whatever the host's load; the demos drive an emulated one through the real
# transports (a pseudo-terminal for the ball-bar and the gauges), so a demo that fails here is a
# reading path that loses data or times out when the host is slow. Target: ≥ 19 of 20 complete.
#
#   bench/acquisition/load_campaign.sh [BALLBAR=build/app/ballbar] [RUNS=20] [HOGS=2]
#
# Prints one line per demo (completed, median and slowest wall time); each failure's last line on stderr.
set -euo pipefail
ballbar=${1:-build/app/ballbar}
runs=${2:-20}
hogs=${3:-2}
[ -x "$ballbar" ] || { echo "no ballbar at $ballbar (build it, or give its path)" >&2; exit 2; }
ballbar=$(realpath "$ballbar")

demos=(
  'ssm-TTTRR:demo --machine TTTRR'
  'ssm-RRTTT:demo --machine RRTTT'
  'circular:demo --test circular'
  'circular-ZX:demo --test circular --plane ZX'
  'sylvac:demo --instrument sylvac'
  'digimatic:demo --instrument digimatic'
  'modbus:demo --instrument modbus'
  'mitutoyo-itn:demo --instrument mitutoyo-itn'
)

work=$(mktemp -d)
hog_pids=()
cleanup() {
  for p in "${hog_pids[@]}"; do kill "$p" 2>/dev/null || true; done
  rm -rf "$work"
}
trap cleanup EXIT
for ((h = 0; h < hogs; ++h)); do
  (while :; do :; done) &
  hog_pids+=($!)
done
sleep 1
echo "load: $hogs busy processes; $(cut -d' ' -f1-3 /proc/loadavg) (1, 5, 15 min) at the start"

printf '%-14s %5s %9s %10s %10s\n' demo runs completed median_s slowest_s
total_failed=0
for entry in "${demos[@]}"; do
  name=${entry%%:*}
  args=${entry#*:}
  ok=0
  times=()
  for ((seed = 1; seed <= runs; ++seed)); do
    db="$work/$name-$seed.db"
    t0=$(date +%s.%N)
    # shellcheck disable=SC2086  # the demo's arguments are words
    if out=$("$ballbar" --db "$db" $args --seed "$seed" 2>&1); then
      ok=$((ok + 1))
    else
      echo "$name seed $seed: $(tail -n 1 <<<"$out" | head -c 400)" >&2
    fi
    t1=$(date +%s.%N)
    times+=("$(echo "$t1 - $t0" | bc)")
    rm -f "$db" "$db"-wal "$db"-shm "$db".lock
  done
  read -r median slowest < <(printf '%s\n' "${times[@]}" | sort -n |
    awk '{ a[NR] = $1 } END { m = (NR % 2) ? a[(NR + 1) / 2] : (a[NR / 2] + a[NR / 2 + 1]) / 2; printf "%.2f %.2f\n", m, a[NR] }')
  printf '%-14s %5d %9d %10s %10s\n' "$name" "$runs" "$ok" "$median" "$slowest"
  total_failed=$((total_failed + runs - ok))
done
echo "load at the end: $(cut -d' ' -f1-3 /proc/loadavg)"
[ "$total_failed" -eq 0 ] || exit 1
