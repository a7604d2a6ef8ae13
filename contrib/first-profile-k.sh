#!/usr/bin/env bash
# The first profile's k against the ten-line scipy script (issue 31): for
# each seed, the long IMU set (30 trials a label, time split 21 + 9) and
# the fingertip set at 50 trials a material (time split 25 + 25), the
# profile `profile new` writes, the same with k = 1 and k = 5, and
# contrib/welch_1nn.py on the same split. One line per seed and set.
# Needs numpy, scipy and pandas; not run by CI.
#
#   contrib/first-profile-k.sh HAPTICLAB OUT [SEEDS]
set -uo pipefail
hl=$(realpath "$1"); out=$(realpath -m "$2"); seeds=${3:-"1 2 3 4 5 6 7 8"}
here=$(cd "$(dirname "$0")" && pwd)
for seed in $seeds; do
  d=$out/$seed; mkdir -p "$d"; cd "$d"
  for set in long finger50; do
    if [ ! -d "rec/$set" ]; then
      case $set in
        long) python3 "$here/rig-sets.py" sets --seed "$seed" --only long >/dev/null
              "$hl" import sets/long/*/*.csv --rate 100 --split 2 --out rec/long >/dev/null 2>&1 ;;
        finger50) python3 "$here/rig-sets.py" sets50 --seed "$seed" --only fingertip --trials 50 >/dev/null
              "$hl" import sets50/fingertip/*/*.csv --rate 2200 --out rec/finger50 >/dev/null 2>&1 ;;
      esac
    fi
    "$hl" profile new --from "rec/$set" --out "$set.toml" --overwrite >/dev/null 2>&1
    if [ "$set" = finger50 ]; then
      # The time split 25 + 25, as the README says for trials recorded in order.
      python3 - <<'PY'
import re
t = open("finger50.toml").read()
t = re.sub(r'\nmethod = "k-fold"\nfolds = \d+\n', '\n', t, count=1)
t = t.replace('[evaluation]\n', '[evaluation]\nmethod = "holdout"\ntrain_per_class = 25\ntest_per_class = 25\n', 1)
open("finger50.toml", "w").write(t)
PY
      scipy=$(python3 "$here/welch_1nn.py" rec/finger50 2200 25 25)
    else
      scipy=$(python3 "$here/welch_1nn.py" rec/long 100 21 9)
    fi
    acc() { "$hl" evaluate "rec/$set" -p "$1" --json 2>/dev/null | python3 -c 'import json,sys; print(round(100*json.load(sys.stdin)["accuracy"],1))'; }
    sed 's/^k = [0-9]*/k = 1/' "$set.toml" > "$set-k1.toml"
    sed 's/^k = [0-9]*/k = 5/' "$set.toml" > "$set-k5.toml"
    echo "$seed $set written $(acc "$set.toml") k1 $(acc "$set-k1.toml") k5 $(acc "$set-k5.toml") scipy $scipy"
  done
done
