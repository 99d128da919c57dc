#!/usr/bin/env bash
# Reactive rendering, measured as a user would see it: starts the app on the default design
# under a virtual X server (software rendering), lets it settle, then reads the processor time
# it uses while nobody touches it. Fails above 10 % of one core.
# Usage: scripts/idle-cpu.sh [settle seconds] [measured seconds]
set -euo pipefail
cd "$(dirname "$0")/.."
export CARGO_TARGET_DIR="${CARGO_TARGET_DIR:-$HOME/.cache/clayloft-target}"
settle="${1:-20}"
span="${2:-20}"
autosave="$(mktemp -d)"
CLAYLOFT_AUTOSAVE_DIR="$autosave" xvfb-run -a -s "-screen 0 1280x720x24" \
  "$CARGO_TARGET_DIR/release/clayloft" assets/designs/petal-vase.toml > "$autosave/app.log" 2>&1 &
wrapper=$!
pid=""
for _ in $(seq 1 100); do
  # `clayloft` hands the window to `clayloft-editor` in the same process, under that name.
  pid="$(pgrep -n -x clayloft-editor || pgrep -n -x clayloft || true)"
  [ -n "$pid" ] && break
  sleep 0.2
done
[ -n "$pid" ] || { echo "idle-cpu: the app did not start"; cat "$autosave/app.log"; exit 1; }
sleep "$settle"
ticks() { awk '{print $14 + $15}' "/proc/$pid/stat"; }
hz="$(getconf CLK_TCK)"
t0="$(ticks)"
sleep "$span"
t1="$(ticks)"
kill "$pid" 2> /dev/null || true
wait "$wrapper" 2> /dev/null || true
percent=$(( (t1 - t0) * 100 / (hz * span) ))
echo "idle-cpu: the app used ${percent} % of one core over ${span} s left alone"
[ "$percent" -lt 10 ]
