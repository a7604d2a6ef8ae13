#!/bin/sh
# hapticlab's `evaluate` against the researcher's numpy/pandas/scikit-learn
# script (contrib/reference.py) on the same recordings, side by side in one
# run: the two alternate (A B A B ...), RUNS times each, so a machine whose
# speed drifts slows both alike. Prints each run's wall, CPU (user + system)
# and peak memory (/usr/bin/time), then the best and the median of each and
# the ratio of the bests. Not run by CI (it needs numpy, pandas and
# scikit-learn, and a release build).
#
#   contrib/compare-evaluate.sh DIR [RUNS] [-- ARGS FOR BOTH]
#
#   cargo build --release
#   target/release/hapticlab simulate --per-class 300 --out /tmp/sim1200
#   contrib/compare-evaluate.sh /tmp/sim1200 3              # the profile's holdout split
#   contrib/compare-evaluate.sh /tmp/sim1200 3 -- --folds 10
#
# Both read and extract every recording under DIR, then split: the holdout
# split uses 10 + 20 scans per texture of however many DIR holds.
set -eu
dir=${1:?usage: compare-evaluate.sh DIR [RUNS] [-- ARGS FOR BOTH]}
runs=${2:-3}
shift
[ $# -gt 0 ] && shift
[ "${1:-}" = "--" ] && shift
here=$(dirname "$0")
bin=${HAPTICLAB:-$here/../target/release/hapticlab}
[ -x "$bin" ] || { echo "compare-evaluate.sh: no $bin (cargo build --release)" >&2; exit 2; }
[ -x /usr/bin/time ] || { echo "compare-evaluate.sh: needs /usr/bin/time (GNU time)" >&2; exit 2; }
log=$(mktemp)
trap 'rm -f "$log"' EXIT
# One warm-up each: the recordings into the page cache, Python's modules too.
"$bin" evaluate "$dir" "$@" >/dev/null 2>&1
python3 "$here/reference.py" "$dir" "$@" >/dev/null 2>&1
i=1
while [ "$i" -le "$runs" ]; do
    /usr/bin/time -f "hapticlab %e %U %S %M" -a -o "$log" "$bin" evaluate "$dir" "$@" >/dev/null
    /usr/bin/time -f "reference %e %U %S %M" -a -o "$log" python3 "$here/reference.py" "$dir" "$@" >/dev/null
    i=$((i + 1))
done
awk '
{ wall[$1, ++n[$1]] = $2; cpu[$1, n[$1]] = $3 + $4; peak[$1, n[$1]] = $5 / 1024
  printf "%-9s run %d: wall %6.2f s, cpu %6.2f s, peak %6.1f MiB\n", $1, n[$1], $2, $3 + $4, $5 / 1024 }
function sorted_at(tool, arr, k,   m, i, j, t, v) {
  m = n[tool]; for (i = 1; i <= m; i++) v[i] = arr[tool, i]
  for (i = 1; i <= m; i++) for (j = i + 1; j <= m; j++) if (v[j] < v[i]) { t = v[i]; v[i] = v[j]; v[j] = t }
  return v[k] }
END {
  for (t = 0; t < 2; t++) {
    tool = t ? "reference" : "hapticlab"; mid = int((n[tool] + 1) / 2)
    best[tool] = sorted_at(tool, wall, 1); cpubest[tool] = sorted_at(tool, cpu, 1)
    printf "%-9s wall best %.2f s, median %.2f s; cpu median %.2f s; peak median %.1f MiB\n", tool,
      best[tool], sorted_at(tool, wall, mid), sorted_at(tool, cpu, mid), sorted_at(tool, peak, mid) }
  printf "hapticlab is %.1fx faster (best wall against best wall), %.1fx less CPU (best against best)\n",
    best["reference"] / best["hapticlab"], cpubest["reference"] / cpubest["hapticlab"] }
' "$log"
