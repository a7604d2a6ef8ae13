#!/usr/bin/env bash
# CPU used by the idle console (servo thread, recorder and UI together), as a
# percentage of one core, over SECONDS (default 30) in a 120x40 tmux window.
# Usage: contrib/measure-idle-cpu.sh [SECONDS]   (needs tmux; builds release first)
set -euo pipefail
cd "$(dirname "$0")/.."
secs=${1:-30}
cargo build --release --quiet
dataset=$(mktemp -d)
session=hapticlab-idle-$$
tmux new-session -d -s "$session" -x 120 -y 40 "target/release/hapticlab console --dataset $dataset"
trap 'tmux kill-session -t "$session" 2>/dev/null || true; rm -rf "$dataset"' EXIT
sleep 3
pid=$(pgrep -n -f "hapticlab console --dataset $dataset")
ticks() { awk '{print $14 + $15}' "/proc/$pid/stat"; }
hz=$(getconf CLK_TCK)
a=$(ticks); sleep "$secs"; b=$(ticks)
awk -v a="$a" -v b="$b" -v hz="$hz" -v s="$secs" \
  'BEGIN { printf "idle console: %.1f %% of one core over %d s\n", (b - a) / hz / s * 100, s }'
