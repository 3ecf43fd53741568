#!/bin/sh
# The memory bound of the analyses that hold a readings file whole (docs/identification.md, "Memory"):
# `identify` and `discover` of a readings file of ROWS readings, each run's peak resident memory against
#   identify  ≤ 32 MiB + 560 bytes per reading
#   discover  ≤ 32 MiB + 1550 bytes per reading
# and a JSON input of 16 MiB holding too many values, refused before it is parsed (≤ 64 MB).
# The readings are written by the independent generator of the discovery benchmark. Needs GNU time
# (/usr/bin/time, Debian package `time`). Exit 1 when a bound is exceeded.
# Usage: memory_bound.sh BALLBAR_EXE BENCH_DISCOVERY_CAMPAIGN_EXE [ROWS=500000]
set -eu
exe=${1:?usage: memory_bound.sh BALLBAR_EXE BENCH_DISCOVERY_CAMPAIGN_EXE [ROWS]}
gen=${2:?usage: memory_bound.sh BALLBAR_EXE BENCH_DISCOVERY_CAMPAIGN_EXE [ROWS]}
rows=${3:-500000}
[ -x /usr/bin/time ] || { echo "memory_bound.sh: needs GNU time (apt-get install time)" >&2; exit 2; }
dir=$(mktemp -d /tmp/ballbar-memory-bench-XXXXXX)
trap 'rm -rf "$dir"' EXIT
"$gen" --write-readings "$dir/readings.csv" "$rows" >/dev/null
bytes=$(wc -c <"$dir/readings.csv")
echo "readings: $rows rows, $((bytes / 1048576)) MiB"
status=0
check() { # LABEL BOUND_KB CMD...
  label=$1
  bound=$2
  shift 2
  rm -f "$dir"/db.sqlite*
  /usr/bin/time -f %M -o "$dir/kb" "$@" >/dev/null 2>"$dir/err" || true
  kb=$(tail -n 1 "$dir/kb")
  verdict=ok
  [ "$kb" -le "$bound" ] || { verdict=EXCEEDED; status=1; }
  case $label in
  identify | discover) per=" ($((kb * 1024 / rows)) bytes per reading)" ;;
  *) per="" ;;
  esac
  echo "$label: peak $((kb / 1024)) MiB, bound $((bound / 1024)) MiB: $verdict$per"
}
check identify $((32768 + rows * 560 / 1024)) "$exe" --db "$dir/db.sqlite" identify "$dir/readings.csv" --json
check discover $((32768 + rows * 1550 / 1024)) "$exe" --db "$dir/db.sqlite" discover "$dir/readings.csv" --json
# Records are counted before the readings' room is reserved: 200 MiB of empty lines, or of lines of
# commas alone, reserve nothing resident and are refused (≤ 64 MiB).
head -n 12 "$dir/readings.csv" | grep '^#' >"$dir/empty.csv"
cp "$dir/empty.csv" "$dir/commas.csv"
yes '' | head -c 209715200 >>"$dir/empty.csv"
yes ',,,,,,,,,,,,,,,,,,' | head -c 209715200 >>"$dir/commas.csv"
check "200 MiB of empty lines (refused)" 65536 "$exe" --db "$dir/db.sqlite" identify "$dir/empty.csv"
check "200 MiB of lines of commas (refused)" 65536 "$exe" --db "$dir/db.sqlite" identify "$dir/commas.csv"
rm -f "$dir/empty.csv" "$dir/commas.csv"
# 16 MiB of "0," (8 M values): parsed, 418 MB; refused by the value count first.
awk 'BEGIN { printf "["; for (i = 0; i < 8388606; i++) printf "0,"; printf "0]" }' >"$dir/flat.json"
check "a 16 MiB JSON machine file of 8 M values (refused)" 65536 "$exe" measure --dry-run --machine "$dir/flat.json"
grep -q "more than 2000000 values" "$dir/err" || { echo "the flat JSON file was not refused: $(cat "$dir/err")"; status=1; }
exit $status
