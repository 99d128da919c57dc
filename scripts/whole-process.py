#!/usr/bin/env python3
"""Times `clayloft gcode` of the benchmark vessel as a whole process, for one or more binaries
run in turn (so that the machine's drifting speed falls on all alike), back to back or after a
pause (a single command after the machine idled, as a potter runs it).

    scripts/whole-process.py OLD_BINARY NEW_BINARY            # 30 rounds back to back
    scripts/whole-process.py --pause 1.5 --rounds 12 OLD NEW  # each run after 1.5 s idle

Prints the minimum, first quartile, median and maximum wall time of each, in ms, and the median
processor time (user and system, both cores together), which a busy shared machine moves less.
With two or more binaries, also each one's wall and processor time over the first's, round by
round, as the median of those ratios: the machine's drift within a round falls on both, so a
change of a few percent shows where the medians of a drifting hour hide it. The order within
a round alternates from round to round.
"""
import argparse
import os
import statistics
import subprocess
import tempfile
import time
from pathlib import Path

DESIGN = Path(__file__).resolve().parent.parent / "assets/benchmarks/vase-720x300.toml"

parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
parser.add_argument("binaries", nargs="+")
parser.add_argument("--rounds", type=int, default=30)
parser.add_argument("--pause", type=float, default=0.0, help="seconds idle before each run")
parser.add_argument("--design", default=str(DESIGN))
args = parser.parse_args()

with tempfile.TemporaryDirectory() as work:
    out = str(Path(work) / "vase.gcode")
    times = {b: [] for b in args.binaries}
    cpu = {b: [] for b in args.binaries}
    for r in range(args.rounds):
        for b in (args.binaries if r % 2 == 0 else args.binaries[::-1]):
            time.sleep(args.pause)
            start = time.perf_counter()
            child = subprocess.Popen([b, "gcode", args.design, "-o", out],
                                     stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
            _, status, usage = os.wait4(child.pid, 0)
            times[b].append((time.perf_counter() - start) * 1000)
            if os.waitstatus_to_exitcode(status) != 0:
                raise SystemExit(f"{b} gcode {args.design} failed")
            cpu[b].append((usage.ru_utime + usage.ru_stime) * 1000)
    first = args.binaries[0]
    for b in args.binaries[1:]:
        wall = statistics.median(t / f for t, f in zip(times[b], times[first]))
        proc = statistics.median(c / f for c, f in zip(cpu[b], cpu[first]) if f > 0)
        print(f"{b} over {first}, round by round: wall {wall:.3f}, processor {proc:.3f} (medians)")
    for b, t in times.items():
        t.sort()
        print(f"{b}: min {t[0]:.1f}  p25 {t[len(t) // 4]:.1f}  "
              f"median {statistics.median(t):.1f}  max {t[-1]:.1f} ms; "
              f"processor median {statistics.median(cpu[b]):.1f} ms")
