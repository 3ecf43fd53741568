#!/bin/sh
# The LinuxCNC loop's gain per axis over several noise seeds and error sets: `ballbar demo --controller
# linuxcnc` (docs/linuxcnc.md "The loop") for each error set (0: the demo's; 1..: random rotary-axis
# location errors of the same size) and each seed, then the gains per axis: each run, min, median, max.
# Each run takes about three minutes (two SSM sessions in real time). Root, LinuxCNC and the module.
# With EXTRA (e.g. "--hidden squareness_XY"), each run also discovers and measures a third time: the gain
# of the last measurement is the one summed up.
# Usage: loop_campaign.sh BALLBAR_EXE MODULE_SO [SEEDS="1 2"] [ERROR_SETS="0 1 2"] [EXTRA=""]
set -eu
exe=${1:?usage: loop_campaign.sh BALLBAR_EXE MODULE_SO [SEEDS] [ERROR_SETS]}
module=${2:?usage: loop_campaign.sh BALLBAR_EXE MODULE_SO [SEEDS] [ERROR_SETS]}
seeds=${3:-"1 2"}
sets=${4:-"0 1 2"}
extra=${5:-}
dir=$(mktemp -d /tmp/ballbar-loop-campaign-XXXXXX)
chmod 755 "$dir"  # LinuxCNC's real-time process (uid 65534) reads the work directories below
trap 'rm -rf "$dir"' EXIT
for set in $sets; do
  for seed in $seeds; do
    out="$dir/set$set-seed$seed.json"
    "$exe" --db "$dir/db.sqlite" demo --controller linuxcnc --json --seed "$seed" --error-set "$set" \
      --module "$module" --work-dir "$dir/work-$set-$seed" $extra > "$out"
    python3 - "$out" "$set" "$seed" <<'PY'
import json, sys
j = json.load(open(sys.argv[1]))
g = " ".join("%s %.1fx (%.2f -> %.3f um)" % (a["axis"], a["gain"], a["before_um"], a["after_um"]) for a in j["axes"])
if j.get("discovery") and j["discovery"]["third_session"]:
    g += " | found %s, third: " % ", ".join(j["discovery"]["discovered"])
    g += " ".join("%s %.1fx (%.3f um)" % (a["axis"], a["third_gain"], a["third_um"]) for a in j["axes"])
c = " ".join("%s G %.2f um" % (c["phase"], c["g_um"]) for c in j.get("circles", []))
print("error set %s seed %s: %s%s" % (sys.argv[2], sys.argv[3], g, " | circle " + c if c else ""), flush=True)
PY
  done
done
python3 - "$dir" <<'PY'
import glob, json, statistics, sys
runs = [json.load(open(f)) for f in sorted(glob.glob(sys.argv[1] + "/set*.json"))]
for k, axis in enumerate("XYZ"):
    g = sorted(r["axes"][k].get("third_gain") or r["axes"][k]["gain"] for r in runs)  # the last measurement's
    print("%s gain over %d runs: min %.1fx  median %.1fx  max %.1fx  (seed: %.1fx)"
          % (axis, len(g), g[0], statistics.median(g), g[-1], runs[0]["axes"][k]["seed_gain"]))
PY
