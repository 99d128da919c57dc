#!/usr/bin/env python3
"""Black-box mutation fuzzing of the `clayloft` command line on the stable toolchain: hostile
designs, G-code files and STL meshes made by mutating the shipped ones, each run through the
commands a user would give it. The bad-input contract (README "Robustness") is asserted for every
run: exit 0, 1 or 2, never a panic or a signal, an error of one line on stderr, and an end within
a bounded time. (The cargo-fuzz targets in `fuzz/` go deeper but need the nightly toolchain.)

    scripts/mutate-inputs.py CLAYLOFT [--runs 300] [--seed 1] [--keep DIR]

Mutations: a design's numbers swapped for extremes (0, −1, 1e308, NaN, inf, 2³¹, …) or scaled
(×0.1 … ×5, negated), one to three at a time; a G-code file's lines cut short, deleted, replaced
by random words or by moves to extreme coordinates; an STL's vertices moved a few millimetres or
overwritten with NaN, infinities and huge values, its triangle count corrupted or the file
truncated. Exits 1 naming each input that broke the
contract (kept in --keep, or a temporary folder that is then not removed).
"""
import argparse
import random
import re
import shutil
import struct
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
EXTREMES = ["0", "-0", "-1", "0.0001", "0.5", "3", "7.77", "360", "-360", "720", "1e9", "-1e9",
            "1e15", "1e308", "-1e308", "1e-308", "2147483648", "4e6", "nan", "inf", "-inf"]
WORDS = ["G1", "G0", "G92", "G90", "G91", "M82", "M83", "X", "Y", "Z", "E", "F", "1e308", "nan",
         "-inf", "99999999", "0", "-5", ";", "(", ")", "*", "N5", "M110", "G28", "T1", "G2", "G3",
         "I5", "J5", "R3"]
LIMIT_S = 60.0  # far above any run on a shipped input (under a second)

parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
parser.add_argument("clayloft")
parser.add_argument("--runs", type=int, default=300)
parser.add_argument("--seed", type=int, default=1)
parser.add_argument("--keep", help="folder for the inputs that break the contract")
args = parser.parse_args()
rng = random.Random(args.seed)
work = Path(tempfile.mkdtemp(prefix="clayloft-mutants-"))
keep = Path(args.keep) if args.keep else work
keep.mkdir(parents=True, exist_ok=True)

designs = sorted((ROOT / "assets/designs").glob("*.toml"))
mesh = (ROOT / "assets/meshes/lobed-vase.stl").read_bytes()
# A real program to mutate: the first shipped design's G-code.
program_path = work / "seed.gcode"
subprocess.run([args.clayloft, "gcode", str(designs[0]), "-o", str(program_path)],
               check=True, capture_output=True)
program = program_path.read_text().split("\n")


def mutant_design(i):
    src = rng.choice(designs).read_text()
    # Contour pictures are found next to the design: make their paths absolute.
    src = src.replace('"../contours/', f'"{ROOT}/assets/contours/')
    numbers = [m for m in re.finditer(r'(?<![A-Za-z_"#\[])-?\d+(\.\d+)?(e-?\d+)?', src)
               if not src[:m.start()].rsplit("\n", 1)[-1].startswith("version")]
    for m in sorted(rng.sample(numbers, min(rng.randint(1, 3), len(numbers))),
                    key=lambda m: -m.start()):
        # Half the time an extreme, else the number scaled (a valid but unusual design).
        # (Whole numbers stay whole: a count given as 2.1 is only a type error.)
        scaled = float(m.group(0)) * rng.choice([0.1, 0.3, 0.7, 1.3, 2.0, 5.0, -1.0])
        if rng.random() < 0.5:
            value = rng.choice(EXTREMES)
        elif re.fullmatch(r"-?\d+", m.group(0)):
            value = str(round(scaled))
        else:
            value = repr(scaled)
        src = src[:m.start()] + value + src[m.end():]
    path = work / f"design-{i}.toml"
    path.write_text(src)
    command = rng.choice([["gcode", str(path), "-o", str(work / "out.gcode")], ["info", str(path)],
                          ["stl", str(path), "-o", str(work / "out.stl")]])
    return path, command


def mutant_program(i):
    lines = list(program[:rng.randint(1, len(program))])
    for _ in range(rng.choice([1, 2, 3, 10, 30])):
        k = rng.randrange(max(1, len(lines)))
        op = rng.random()
        if op < 0.3 and lines:
            lines[k] = " ".join(rng.choice(WORDS) + rng.choice(["", "1", "-3.5", "1e9", "nan"])
                                for _ in range(rng.randint(1, 6)))
        elif op < 0.5 and lines:
            del lines[k]
        elif op < 0.7:
            values = [rng.choice(["0", "1e300", "-1e300", "nan", "5", "150.0001", "1e-320"])
                      for _ in range(4)]
            lines.insert(k, "G1 X{} Y{} Z{} E{}".format(*values))
        elif lines:
            lines[k] = lines[k][:rng.randint(0, len(lines[k]))]
    path = work / f"program-{i}.gcode"
    path.write_text("\n".join(lines))
    command = ["check", str(path)]
    if rng.random() < 0.5:
        command += ["--design", str(rng.choice(designs))]
    return path, command


def mutant_mesh(i):
    data = bytearray(mesh[:rng.randint(0, len(mesh))] if rng.random() < 0.3 else mesh)
    for _ in range(rng.randint(1, 20)):
        if len(data) > 88:
            k = rng.randrange(84, len(data) - 4)
            if rng.random() < 0.5:
                # A vertex moved a little: a dent, a fold, a crossing.
                (old,) = struct.unpack("<f", data[k:k + 4])
                value = old + rng.uniform(-5.0, 5.0) if old == old else 0.0
            else:
                value = rng.choice([float("nan"), 1e30, -1e30, 0.0, float("inf"), 1e-40,
                                    rng.uniform(-1e3, 1e3)])
            data[k:k + 4] = struct.pack("<f", value)
    if rng.random() < 0.2 and len(data) >= 84:
        data[80:84] = struct.pack("<I", rng.choice([0, 1, 2**31, 2**32 - 1, 10**7]))
    path = work / f"mesh-{i}.stl"
    path.write_bytes(bytes(data))
    command = rng.choice([["gcode", str(path), "-o", str(work / "out.gcode")], ["info", str(path)],
                          ["stl", str(path), "-o", str(work / "out.stl")]])
    return path, command


broken = []
outcomes = {}  # (command, exit code) → runs
for i in range(args.runs):
    path, command = rng.choice([mutant_design, mutant_program, mutant_mesh])(i)
    start = time.perf_counter()
    try:
        run = subprocess.run([args.clayloft] + command, capture_output=True, text=True,
                             errors="replace", timeout=LIMIT_S)
        code, err = run.returncode, run.stderr
    except subprocess.TimeoutExpired:
        code, err = "timeout", ""
    seconds = time.perf_counter() - start
    outcomes[(command[0], code)] = outcomes.get((command[0], code), 0) + 1
    why = None
    if code not in (0, 1, 2):
        why = f"exit {code}"
    elif "panicked" in err:
        why = "panic"
    elif code == 2 and len(err.strip().splitlines()) != 1:
        why = f"an error of {len(err.strip().splitlines())} lines"
    if why:
        kept = keep / path.name
        if kept != path:
            kept.write_bytes(path.read_bytes())
        broken.append(f"{kept}: clayloft {' '.join(command[:1])}: {why} ({seconds:.1f} s): "
                      f"{err.strip()[-300:]}")
        print(broken[-1], flush=True)
    else:
        path.unlink()
print("runs by command and exit code:",
      ", ".join(f"{c} {e}: {n}" for (c, e), n in sorted(outcomes.items(), key=str)))
print(f"{args.runs} mutated inputs (seed {args.seed}): {len(broken)} broke the contract")
if not broken or keep != work:
    shutil.rmtree(work)
sys.exit(1 if broken else 0)
