#!/usr/bin/env bash
# The README's multi-seed figures for "Your own rig's data": for each seed
# and generated set, the README's commands (import, profile new, the
# [evaluation] the README says to choose, evaluate, tune with its default
# budget) and one line "seed set first outer inner chosen…", then each
# set's mean and range. Not run by CI (needs numpy and scipy for
# contrib/rig-sets.py).
#
#   contrib/tune-seeds.sh OUT [HAPTICLAB] [SEEDS] [SETS] [-- TUNE ARGS…]
#
# e.g. contrib/tune-seeds.sh /tmp/seeds target/release/hapticlab "1 2 3 4 5 6 7 8" "noise finger long"
# (sound: leave-one-out over 56 clips, minutes a seed). OUT/SEED keeps the
# sets, recordings, profiles and each tune's JSON, so a second run only tunes.
set -euo pipefail
out=$(realpath -m "$1")
hl=$(realpath "${2:-target/release/hapticlab}")
seeds=${3:-"1 2 3 4 5 6 7 8"}
sets=${4:-"noise sound finger long"}
shift $(($# < 4 ? $# : 4))
[ "${1:-}" = "--" ] && shift
here=$(cd "$(dirname "$0")" && pwd)
# tee opens OUT/lines.txt before the first seed makes OUT.
mkdir -p "$out"
for seed in $seeds; do
  d=$out/$seed
  mkdir -p "$d"
  cd "$d"
  for set in $sets; do
    if [ ! -d "rec/$set" ]; then
      case $set in
        noise) python3 "$here/rig-sets.py" sets --seed "$seed" --only noise
          "$hl" import sets/noise/*/*.csv --rate 1000 --out rec/noise >/dev/null 2>&1 ;;
        sound) python3 "$here/rig-sets.py" sets --seed "$seed" --only sound
          "$hl" import sets/sound/*/*.wav --out rec/sound --gzip >/dev/null 2>&1 ;;
        finger) python3 "$here/rig-sets.py" sets --seed "$seed" --only fingertip
          "$hl" import sets/fingertip/*/*.csv --rate 2200 --out rec/finger >/dev/null 2>&1 ;;
        long) python3 "$here/rig-sets.py" sets --seed "$seed" --only long
          "$hl" import sets/long/*/*.csv --rate 100 --split 2 --out rec/long >/dev/null 2>&1 ;;
        *) echo "tune-seeds.sh: no set $set (noise, sound, finger, long)" >&2; exit 2 ;;
      esac
    fi
    if [ ! -f "$set.toml" ]; then
      "$hl" profile new --from "rec/$set" --out "$set.toml" >/dev/null 2>&1
      # The fingertip trials were recorded in order and drift: the README
      # says to uncomment the fixed split in time (and comment out k-fold).
      if [ "$set" = finger ]; then
        python3 - <<'PY'
t = open("finger.toml").read()
t = t.replace('\nmethod = "k-fold"\nfolds = 10\n', '\n# method = "k-fold"\n# folds = 10\n', 1)
t = t.replace('# method = "holdout"\n# train_per_class = 5\n# test_per_class = 5',
              'method = "holdout"\ntrain_per_class = 5\ntest_per_class = 5', 1)
open("finger.toml", "w").write(t)
PY
      fi
    fi
    first=$("$hl" evaluate "rec/$set" -p "$set.toml" --json 2>/dev/null |
      python3 -c 'import json,sys; print(round(100*json.load(sys.stdin)["accuracy"],1))')
    "$hl" tune "rec/$set" -p "$set.toml" --out "$set-tuned.toml" --overwrite --json "$@" \
      2>/dev/null >"$set-tune.json"
    python3 - "$seed" "$set" "$first" "$set-tune.json" <<'PY'
import json, sys
seed, name, first, path = sys.argv[1:]
d = json.load(open(path))
chosen = " ".join(v for _, v in d["chosen"]["options"])
print(seed, name, first, round(100 * d["outer_accuracy"], 1),
      round(100 * d["chosen"]["inner_accuracy"], 1), chosen, flush=True)
PY
  done
done | tee "$out/lines.txt"
python3 - "$out/lines.txt" <<'PY'
import collections, sys
rows = collections.defaultdict(list)
for line in open(sys.argv[1]):
    f = line.split()
    rows[f[1]].append((float(f[2]), float(f[3])))
for name, r in rows.items():
    first = [a for a, _ in r]
    outer = [b for _, b in r]
    worse = sum(b < a for a, b in r)
    same = sum(b == a for a, b in r)
    print(f"{name}: {len(r)} seeds; first profile {sum(first)/len(r):.1f} % "
          f"({min(first):.1f}-{max(first):.1f}); tune's outer {sum(outer)/len(r):.1f} % "
          f"({min(outer):.1f}-{max(outer):.1f}); tune worse on {worse}, the same on {same}")
PY
