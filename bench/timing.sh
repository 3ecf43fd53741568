# Shared by the whole-process benchmark scripts (sourced, POSIX sh).
# time_runs RUNS LABEL CMD...: runs CMD RUNS times, prints each wall time and the median with LABEL.
# CMD's stdout goes to $TIME_RUNS_OUT (default /dev/null; the last run's is what stays there). A
# `before_run` function, when defined, is called before each run.
time_runs() {
  _runs=$1
  _label=$2
  shift 2
  _times=""
  _i=0
  while [ "$_i" -lt "$_runs" ]; do
    if command -v before_run >/dev/null 2>&1; then before_run; fi
    _t0=$(date +%s.%N)
    "$@" >"${TIME_RUNS_OUT:-/dev/null}"
    _t1=$(date +%s.%N)
    _t=$(echo "$_t1 - $_t0" | bc)
    echo "run $((_i + 1)): ${_t} s"
    _times="$_times $_t"
    _i=$((_i + 1))
  done
  echo "$_times" | tr ' ' '\n' | grep -v '^$' | sort -n | awk -v label="$_label" '{ a[NR] = $1 } END {
    m = (NR % 2) ? a[(NR + 1) / 2] : (a[NR / 2] + a[NR / 2 + 1]) / 2; printf "median: %.3f s (%s)\n", m, label }'
}
