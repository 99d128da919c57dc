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

    scripts/whole-process.py --placement PROBE OLD NEW        # rounds by where the cores sit

With `--placement`, PROBE (the core-to-core round trip in ns, built with `cargo build --release
-p clayloft-core --example core_round_trip`) runs before and after each round, and the figures
are given apart for rounds whose two cores share a cache (under 200 ns both times) and rounds
whose cores the host has placed apart (over 200 ns both times); rounds that changed placement
midway are left out. On the development machine the placement changes every few seconds to
minutes and moves `clayloft gcode` by a fifth to a half, more than most changes measured.
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
parser.add_argument("--placement", metavar="PROBE", help="core_round_trip example: rounds by placement")
args = parser.parse_args()

# A round trip above this, ns, means the two cores share no cache (see --placement).
APART_NS = 200


def placement():
    """Where the cores sit now: "near", "apart", or "" without a probe."""
    if not args.placement:
        return ""
    said = subprocess.run([args.placement], capture_output=True, text=True, check=True).stdout
    return "apart" if float(said) > APART_NS else "near"


def report(label, times, cpu):
    """The figures of rounds whose times are `times` and processor times `cpu`."""
    if label:
        print(f"{label}: {len(times[args.binaries[0]])} rounds")
    first = args.binaries[0]
    for b in args.binaries[1:]:
        wall = statistics.median(t / f for t, f in zip(times[b], times[first]))
        proc = statistics.median(c / f for c, f in zip(cpu[b], cpu[first]) if f > 0)
        print(f"{b} over {first}, round by round: wall {wall:.3f}, processor {proc:.3f} (medians)")
    for b, t in times.items():
        t = sorted(t)
        print(f"{b}: min {t[0]:.1f}  p25 {t[len(t) // 4]:.1f}  "
              f"median {statistics.median(t):.1f}  max {t[-1]:.1f} ms; "
              f"processor median {statistics.median(cpu[b]):.1f} ms")


with tempfile.TemporaryDirectory() as work:
    out = str(Path(work) / "vase.gcode")
    kinds = ["near", "apart"] if args.placement else [""]
    times = {k: {b: [] for b in args.binaries} for k in kinds}
    cpu = {k: {b: [] for b in args.binaries} for k in kinds}
    for r in range(args.rounds):
        before = placement()
        round_times, round_cpu = {}, {}
        for b in (args.binaries if r % 2 == 0 else args.binaries[::-1]):
            time.sleep(args.pause)
            start = time.perf_counter()
            child = subprocess.Popen([b, "gcode", args.design, "-o", out],
                                     stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
            _, status, usage = os.wait4(child.pid, 0)
            round_times[b] = (time.perf_counter() - start) * 1000
            if os.waitstatus_to_exitcode(status) != 0:
                raise SystemExit(f"{b} gcode {args.design} failed")
            round_cpu[b] = (usage.ru_utime + usage.ru_stime) * 1000
        if placement() != before:
            continue
        for b in args.binaries:
            times[before][b].append(round_times[b])
            cpu[before][b].append(round_cpu[b])
    for k in kinds:
        if times[k][args.binaries[0]]:
            report(k, times[k], cpu[k])
