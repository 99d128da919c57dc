#!/usr/bin/env bash
# Writes what `clayloft gcode` and `clayloft check` say about every shipped design, mesh and the
# benchmark vase (and a wild variant of it with 86° overhangs and enforcement off) into OUTDIR,
# one text file per design and command. Run it before and after a change to the checker or the
# pipeline and compare: `diff -r before after` must be empty for a change that claims to be
# exact (a speed-up, a refactor).
#
#   scripts/check-reports.sh /tmp/before   # on the old commit (or CLAYLOFT_BIN=old-binary)
#   scripts/check-reports.sh /tmp/after    # on the new one
#   diff -r /tmp/before /tmp/after
set -euo pipefail
cd "$(dirname "$0")/.."
out=${1:?usage: scripts/check-reports.sh OUTDIR}
mkdir -p "$out"
target=${CARGO_TARGET_DIR:-$HOME/.cache/clayloft-target}
# CLAYLOFT_BIN names another build to report on (an old commit's binary kept for the comparison)
# without building this checkout.
if [ -n "${CLAYLOFT_BIN:-}" ]; then
  bin="$CLAYLOFT_BIN"
else
  cargo build --release --quiet
  bin="$target/release/clayloft"
fi
wild="$out/wild.toml"
# The benchmark vase pushed past every limit: texture amplitude 6 mm, rose amplitude 20 mm.
sed -e 's/^amplitude = 0.8/amplitude = 6.0/' -e 's/^amplitude = 8.0/amplitude = 20.0/' \
  assets/benchmarks/vase-720x300.toml > "$wild"
printf '[constraints]\nenforce = false\n' >> "$wild"
for f in assets/designs/*.toml assets/benchmarks/*.toml assets/meshes/*.stl "$wild"; do
  n=$(basename "$f"); n=${n%.*}
  gcode="$out/$n.gcode"
  # Each report ends with the command's exit code; the folder is left out of the paths.
  code=0; "$bin" gcode "$f" -o "$gcode" > "$out/$n.gcode.txt" 2>&1 || code=$?
  echo "exit $code" >> "$out/$n.gcode.txt"
  if [ -f "$gcode" ]; then
    code=0; "$bin" check "$gcode" > "$out/$n.check.txt" 2>&1 || code=$?
    echo "exit $code" >> "$out/$n.check.txt"
    rm -f "$gcode"
  fi
  sed -i "s#$out/##g" "$out/$n".*.txt
done
rm -f "$wild"
echo "reports of $(ls "$out"/*.gcode.txt | wc -l) designs in $out"
