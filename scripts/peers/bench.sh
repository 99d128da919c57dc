#!/usr/bin/env bash
# Times the peers on the benchmark vessel, on this machine, beside `clayloft gcode` (issue 14
# item 5): PrusaSlicer's spiral vase slicing Clayloft's STL of the vessel, and FullControl writing
# the same spiral (Clayloft's points as fc.Point steps; only FullControl's transform and file
# write are timed). Not part of CI: it installs PrusaSlicer (Debian) and FullControl (PyPI).
#   scripts/peers/bench.sh            # three runs of each, wall-clock seconds
set -euo pipefail
cd "$(dirname "$0")/../.."
target="${CARGO_TARGET_DIR:-$HOME/.cache/clayloft-target}"
clayloft="$target/release/clayloft"
[ -x "$clayloft" ] || cargo build --release -p clayloft
as_root() { if [ "$(id -u)" = 0 ]; then "$@"; else sudo "$@"; fi; }
command -v prusa-slicer >/dev/null || as_root apt-get install -y --no-install-recommends prusa-slicer
venv="${PEERS_VENV:-$target/peers-venv}"
[ -x "$venv/bin/python" ] || { python3 -m venv "$venv" && "$venv/bin/pip" install -q fullcontrol; }
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
design=assets/benchmarks/vase-720x300.toml
"$clayloft" stl "$design" -o "$work/vase.stl" >/dev/null
secs() { /usr/bin/time -f %e "$@" 2>&1 >/dev/null | tail -n1; }
for run in 1 2 3; do
  echo "run $run"
  echo "  clayloft gcode:            $(secs "$clayloft" gcode "$design" -o "$work/vase.gcode") s"
  echo "  prusa-slicer spiral vase:  $(secs prusa-slicer --export-gcode --spiral-vase \
      --nozzle-diameter 3 --extrusion-width 3 --layer-height 0.5 --first-layer-height 0.5 \
      --perimeters 1 --bottom-solid-layers 2 --top-solid-layers 0 --fill-density 0 \
      --bed-shape 0x0,300x0,300x300,0x300 --center 150,150 --max-print-height 400 \
      -o "$work/prusa.gcode" "$work/vase.stl") s"
  echo "  fullcontrol (transform):   $("$venv/bin/python" scripts/peers/fullcontrol_spiral.py \
      "$work/vase.gcode" "$work/fc.gcode")"
done
