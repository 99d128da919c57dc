#!/usr/bin/env python3
"""How many times faster `clayloft gcode` is than the peers on the benchmark vessel (issue 14
item 5), measured in the same minutes: each round runs Clayloft's whole process `--clayloft-runs`
times, then PrusaSlicer's spiral vase once, then FullControl's transform once, so that the
machine's drifting speed falls on all three alike. Called by `bench.sh`, which installs the peers.

    ratios.py CLAYLOFT PRUSA_SLICER FC_PYTHON WORK_DIR [--rounds 5] [--clayloft-runs 10]
              [--placement PROBE]

Prints each round's times, then the medians and minimums of each tool (ms) and the ratios of
median to median and of minimum to minimum. Clayloft is timed as a whole process (start to exit,
`os.wait4`); PrusaSlicer as a whole process too; FullControl only for its own work (steps to
G-code text to file, timed inside Python by `fullcontrol_spiral.py`, which reads the points
from Clayloft's G-code first).

With `--placement PROBE` (the core-to-core round trip in ns: `cargo build --release -p
clayloft-core --example core_round_trip`), the probe runs before and after each Clayloft run,
and the Clayloft runs whose two cores shared a cache both times (under 200 ns) and those whose
cores the host placed apart (over 200 ns both times) are also given apart, with their ratios to
the peers' medians. On the development machine, a virtual machine, the host moves the two
virtual cores between sharing a cache and not every few seconds to minutes, which moves
`clayloft gcode` by a fifth (a potter's own machine has its cores on one chip).

Each round's first Clayloft run after the peers' is also given apart from the runs after its own.
The development machine's memory balloon reports the memory a process frees to the host once it
has been free for about two seconds, and the host takes it back: the next process to be given it
waits for the host to supply it again, about 4.6 ms a 2 MB page against 0.17 ms to clear one
(measured inside `clayloft gcode`, 2026-12-07). After the peers' six seconds every free page has
been reported, and that run takes a third longer to twice as long (the whole process 52–81 ms
against about 40 ms); a potter's own machine has no such balloon.
"""
import argparse
import os
import re
import statistics
import subprocess
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent.parent
DESIGN = ROOT / "assets/benchmarks/vase-720x300.toml"

parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
parser.add_argument("clayloft")
parser.add_argument("prusa_slicer")
parser.add_argument("fc_python")
parser.add_argument("work")
parser.add_argument("--rounds", type=int, default=5)
parser.add_argument("--clayloft-runs", type=int, default=10)
parser.add_argument("--placement", metavar="PROBE",
                    help="core_round_trip example: Clayloft's runs also given by placement")
args = parser.parse_args()
if args.rounds < 1 or args.clayloft_runs < 1:
    parser.error("--rounds and --clayloft-runs must be at least 1")
work = Path(args.work)


def wall_ms(cmd):
    """Runs `cmd` to its end, its output discarded; its wall time in ms (fails loudly)."""
    start = time.perf_counter()
    child = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    _, status, _ = os.wait4(child.pid, 0)
    elapsed = (time.perf_counter() - start) * 1000
    if os.waitstatus_to_exitcode(status) != 0:
        raise SystemExit(f"failed: {' '.join(map(str, cmd))}")
    return elapsed


clayloft_gcode = work / "vase.gcode"
prusa = [args.prusa_slicer, "--export-gcode", "--spiral-vase",
         "--nozzle-diameter", "3", "--extrusion-width", "3", "--layer-height", "0.5",
         "--first-layer-height", "0.5", "--perimeters", "1", "--bottom-solid-layers", "2",
         "--top-solid-layers", "0", "--fill-density", "0",
         "--bed-shape", "0x0,300x0,300x300,0x300", "--center", "150,150",
         "--max-print-height", "400", "-o", str(work / "prusa.gcode"), str(work / "vase.stl")]
fullcontrol = [args.fc_python, str(ROOT / "scripts/peers/fullcontrol_spiral.py"),
               str(clayloft_gcode), str(work / "fc.gcode")]

# A round trip above this, ns, means the two cores share no cache (see --placement).
APART_NS = 200


def placement():
    """Where the cores sit now: "together" or "apart" (by the probe's round trip)."""
    said = subprocess.run([args.placement], capture_output=True, text=True, check=True).stdout
    return "apart" if int(said.split()[0]) > APART_NS else "together"


def clayloft_run(placed):
    """One `clayloft gcode` run, its wall time; with a probe, filed by placement in `placed`."""
    before = placement() if args.placement else None
    ms = wall_ms([args.clayloft, "gcode", str(DESIGN), "-o", str(clayloft_gcode)])
    if args.placement and placement() == before:
        placed[before].append(ms)
    return ms


times = {"clayloft": [], "prusaslicer": [], "fullcontrol": []}
placed = {"together": [], "apart": []}
# Each round's first Clayloft run after the peers' (see the module's documentation).
firsts = []
for r in range(args.rounds):
    ours = [clayloft_run(placed) for _ in range(args.clayloft_runs)]
    times["clayloft"] += ours
    times["prusaslicer"].append(wall_ms(prusa))
    said = subprocess.run(fullcontrol, capture_output=True, text=True, check=True).stdout
    seconds = re.search(r"points, ([0-9.]+) s", said)
    if not seconds:
        raise SystemExit(f"fullcontrol_spiral.py said: {said!r}")
    times["fullcontrol"].append(float(seconds.group(1)) * 1000)
    if r > 0:
        firsts.append(ours[0])
    print(f"round {r + 1}: clayloft median {statistics.median(ours):.1f} ms, "
          f"prusaslicer {times['prusaslicer'][-1]:.0f} ms, "
          f"fullcontrol {times['fullcontrol'][-1]:.0f} ms")

median = {k: statistics.median(v) for k, v in times.items()}
least = {k: min(v) for k, v in times.items()}
for k in times:
    print(f"{k}: median {median[k]:.1f} ms, minimum {least[k]:.1f} ms ({len(times[k])} runs)")
for peer, goal in (("prusaslicer", 100), ("fullcontrol", 50)):
    print(f"clayloft vs {peer}: {median[peer] / median['clayloft']:.0f}x median to median, "
          f"{least[peer] / least['clayloft']:.0f}x minimum to minimum (goal {goal}x)")
for where, runs in placed.items():
    if runs:
        m = statistics.median(runs)
        print(f"clayloft, cores {where}: median {m:.1f} ms ({len(runs)} runs): "
              f"{median['prusaslicer'] / m:.0f}x prusaslicer, "
              f"{median['fullcontrol'] / m:.0f}x fullcontrol (the peers' medians)")
rest = [ms for i, ms in enumerate(times["clayloft"]) if i % args.clayloft_runs != 0]
if firsts and rest:
    print(f"clayloft, first run after the peers: median {statistics.median(firsts):.1f} ms "
          f"({len(firsts)} runs); runs after its own: median {statistics.median(rest):.1f} ms "
          f"({len(rest)} runs)")
