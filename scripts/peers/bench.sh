#!/usr/bin/env bash
# Times the peers on the benchmark vessel, on this machine, beside `clayloft gcode` (issue 14
# item 5): PrusaSlicer's spiral vase slicing Clayloft's STL of the vessel, and FullControl writing
# the same spiral (Clayloft's points as fc.Point steps; only FullControl's transform and file
# write are timed). Not part of CI: it installs PrusaSlicer (Debian) and FullControl (PyPI).
#   scripts/peers/bench.sh                 # five rounds: ratios of medians and of minimums
#   scripts/peers/bench.sh --rounds 10     # (options of scripts/peers/ratios.py)
#   scripts/peers/bench.sh --placement "$CARGO_TARGET_DIR/release/examples/core_round_trip"
#                                          # also Clayloft's runs by where the cores sit (build
#                                          # the probe: cargo build --release -p clayloft-core
#                                          # --example core_round_trip)
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
# Rounds of ten `clayloft gcode` runs, one PrusaSlicer run and one FullControl run, the ratios
# of their medians and of their minimums at the end (ratios.py).
"$venv/bin/python" scripts/peers/ratios.py "$clayloft" prusa-slicer "$venv/bin/python" "$work" "$@"
