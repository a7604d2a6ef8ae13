#!/bin/sh
# Issue 13's comparison on the generated rig sets: for each setting, the
# accuracy of contrib/reference.py and of `hapticlab evaluate` on the same
# imported recordings. Not run by CI (needs numpy, scipy, pandas, scikit-learn).
#
#   contrib/rig-compare.sh OUT [HAPTICLAB]
#
# writes the sets (contrib/rig-sets.py OUT/sets), imports them to OUT/rec,
# writes one profile per setting to OUT/profiles and prints
# "setting  reference  hapticlab". Sound: leave-one-out over 56 clips;
# fingertip: time split (first 5 trials of each material train, last 5 test).
# The profiles are analysis-only: name, [analysis], [classifier], [evaluation].
set -eu
out=$1
hl=${2:-target/release/hapticlab}
here=$(dirname "$0")
[ -d "$out/sets" ] || python3 "$here/rig-sets.py" "$out/sets"
[ -d "$out/rec/sound" ] || "$hl" import "$out"/sets/sound/*/*.wav --out "$out/rec/sound" >/dev/null
[ -d "$out/rec/fingertip" ] || "$hl" import "$out"/sets/fingertip/*/*.csv --rate 2200 --out "$out/rec/fingertip" >/dev/null
mkdir -p "$out/profiles"
sound='channel = "ch1"
axis = "t_s"
window = [0.0, 4.99]
spacing = 0.000022675736961451247
taper = "hann"'
finger='channel = "vib"
axis = "t_s"
window = [0.0, 5.99]
spacing = 0.00045454545454545455
taper = "hann"'
loo='train_per_class = 3
test_per_class = 1
method = "leave-one-out"'
split='train_per_class = 5
test_per_class = 5'
profile() { # name analysis evaluation
  printf 'name = "%s"\n\n[analysis]\n%s\n\n[classifier]\nk = 1\nstandardize = %s\n\n[evaluation]\n%s\n' \
    "$1" "$2" "${4:-true}" "$3" >"$out/profiles/$1.toml"
}
profile sound-welch "$sound
spectrum = \"welch\"
welch_segment = 2048
bins = [1, 1024]" "$loo"
profile sound-log-power "$sound
spectrum = \"log-power\"
band = [20.0, 20000.0]" "$loo"
profile sound-log-welch "$sound
spectrum = \"log-welch\"
welch_segment = 2048
bins = [1, 1024]" "$loo"
profile sound-log-welch-windows "$sound
spectrum = \"log-welch\"
welch_segment = 2048
bins = [1, 1024]
windows = { length = 0.5, hop = 0.25 }" "$loo"
profile sound-bands-windows "$sound
spectrum = \"log-welch\"
welch_segment = 2048
bands = { count = 32, from = 200.0, to = 20000.0 }
windows = { length = 0.5, hop = 0.25 }" "$loo"
profile sound-cepstra-windows "$sound
spectrum = \"log-welch\"
welch_segment = 2048
bands = { count = 32, from = 200.0, to = 20000.0 }
cepstra = 20
windows = { length = 0.5, hop = 0.25 }" "$loo"
profile finger-welch "$finger
spectrum = \"welch\"
welch_segment = 256
bins = [1, 128]" "$split"
profile finger-log-power "$finger
spectrum = \"log-power\"
bins = [1, 6589]" "$split"
profile finger-log-welch "$finger
spectrum = \"log-welch\"
welch_segment = 256
bins = [1, 128]" "$split"
profile finger-bands "$finger
spectrum = \"log-welch\"
welch_segment = 256
bands = { count = 16, from = 60.0, to = 1000.0 }" "$split"
profile finger-cepstra "$finger
spectrum = \"log-welch\"
welch_segment = 256
bands = { count = 16, from = 60.0, to = 1000.0 }
cepstra = 12" "$split"
# The README's "Your own rig's data": cepstra without c0, unstandardised,
# with and without sub-windows of a tenth of the clip / two Welch segments.
profile sound-readme "$sound
spectrum = \"log-welch\"
welch_segment = 2048
bands = { count = 32, from = 86.1, to = 22000.0, scale = \"log\" }
cepstra = 13
drop_level = true
windows = { length = 0.499, hop = 0.249 }" "$loo" false
profile finger-readme-cepstra "$finger
spectrum = \"log-welch\"
welch_segment = 2048
bands = { count = 32, from = 4.29, to = 1100.0, scale = \"log\" }
cepstra = 13
drop_level = true" "$split" false
profile finger-readme-windows "$finger
spectrum = \"log-welch\"
welch_segment = 2048
bands = { count = 32, from = 4.29, to = 1100.0, scale = \"log\" }
cepstra = 13
drop_level = true
windows = { length = 1.86, hop = 0.93 }" "$split" false
profile finger-log-welch-windows "$finger
spectrum = \"log-welch\"
welch_segment = 2048
bins = [1, 1024]
windows = { length = 1.86, hop = 0.93 }" "$split" false
printf '%-26s %-22s %s\n' setting reference hapticlab
for p in "$out"/profiles/*.toml; do
  name=$(basename "$p" .toml)
  case $name in sound-*) rec=$out/rec/sound ;; *) rec=$out/rec/fingertip ;; esac
  ref=$(python3 "$here/reference.py" "$rec" --profile "$p" 2>&1 | tail -1 | sed -n 's/^accuracy: \([^ ]*\) (\([^)]*\)).*/\1 (\2)/p')
  ours=$("$hl" evaluate "$rec" -p "$p" 2>&1 | sed -n 's/^accuracy: \([^ ]*\) (\([^)]*\)).*/\1 (\2)/p' | head -1)
  printf '%-26s %-22s %s\n' "$name" "${ref:-failed}" "${ours:-not available}"
done
