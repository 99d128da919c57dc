#!/usr/bin/env python3
"""Times the handle drags of issue 14 item 5 (`cargo bench -p clayloft-model --bench recompute`)
in short sittings, each filed by where the host placed the machine's two cores during it.

    scripts/drags-by-placement.py PROBE                 # 20 sittings of 2 s per drag
    scripts/drags-by-placement.py PROBE --sittings 40 --seconds 3

PROBE is the core-to-core round trip in ns (`cargo build --release -p clayloft-core --example
core_round_trip`). It runs before and after each sitting; a sitting whose two cores shared a
cache both times (under 200 ns) is filed "together", one whose cores were apart both times
(over 200 ns) "apart", and one that changed placement midway is left out. On the development
machine, a virtual machine, the host moves the two cores between the two every few seconds to
minutes: apart, a drag's session update on two cores is no faster than on one
(`docs/benchmark-log.md`, twenty-fourth sitting), and one `cargo bench` run of a few seconds
mixes the two. A potter's own machine has its cores on one chip.

Prints, for each drag and placement, the median and range of the sittings' criterion
estimates (ms) and how many sittings there were. Builds the benchmark first (as `cargo bench`
would, in the shared target directory).
"""
import argparse
import json
import re
import statistics
import subprocess
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
DRAGS = [
    "drag_local_line_360x200_recompute_and_mesh",
    "drag_upper_contour_360x200_recompute_and_mesh",
]
# A round trip above this, ns, means the two cores share no cache.
APART_NS = 200

parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
parser.add_argument("probe", help="the core_round_trip example")
parser.add_argument("--sittings", type=int, default=20)
parser.add_argument("--seconds", type=float, default=2.0, help="criterion's measurement time")
args = parser.parse_args()
if args.sittings < 1 or args.seconds <= 0:
    parser.error("--sittings must be at least 1 and --seconds above 0")


def bench_binary():
    """The recompute benchmark's executable, built as `cargo bench` builds it."""
    out = subprocess.run(
        ["cargo", "bench", "-p", "clayloft-model", "--bench", "recompute", "--no-run",
         "--message-format=json"],
        cwd=ROOT, capture_output=True, text=True, check=True).stdout
    for line in out.splitlines():
        msg = json.loads(line)
        if msg.get("reason") == "compiler-artifact" and msg["target"]["name"] == "recompute" \
                and msg.get("executable"):
            return msg["executable"]
    raise SystemExit("cargo built no recompute benchmark")


def placement():
    """"together" or "apart", by the probe's round trip."""
    said = subprocess.run([args.probe], capture_output=True, text=True, check=True).stdout
    return "apart" if float(said) > APART_NS else "together"


TIME = re.compile(r"time:\s+\[\S+ \S+ (\S+) (\S+) \S+ \S+\]")
UNIT = {"ns": 1e-6, "µs": 1e-3, "us": 1e-3, "ms": 1.0, "s": 1e3}

binary = bench_binary()
estimates = {}  # (drag, placement) -> [ms]
for sitting in range(args.sittings):
    for drag in DRAGS:
        before = placement()
        out = subprocess.run(
            [binary, "--bench", drag, "--warm-up-time", "1",
             "--measurement-time", str(args.seconds)],
            cwd=ROOT / "plugins/clayloft-model", capture_output=True, text=True, check=True).stdout
        if placement() != before:
            continue
        m = TIME.search(out)
        if m:
            estimates.setdefault((drag, before), []).append(float(m.group(1)) * UNIT[m.group(2)])

for drag in DRAGS:
    for where in ("together", "apart"):
        ms = estimates.get((drag, where), [])
        if ms:
            print(f"{drag}, cores {where}: median {statistics.median(ms):.2f} ms "
                  f"({min(ms):.2f}–{max(ms):.2f}, {len(ms)} sittings)")
        else:
            print(f"{drag}, cores {where}: no sitting")
