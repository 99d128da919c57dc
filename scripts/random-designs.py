#!/usr/bin/env python3
"""Writes random designs (SPEC §6) for hunting print defects nobody thought of: random contours
(circle, ellipse, polygon, star, rose, spline), zero to two vertical control lines, sometimes a
horizontal one, a texture, a second bead, enforcement off. Each seed gives the same design.

    scripts/random-designs.py OUT_DIR FIRST_SEED END_SEED
    for f in OUT_DIR/*.toml; do clayloft gcode "$f" -o "${f%.toml}.gcode"; done

Then look at what was written (loops in the path, refusals, times) and at what was refused. The
2026-12-06 hunt (seeds 0–449) found textures folding sharp tips into loops (README, `[texture]`).
"""
import math
import os
import random
import sys


def contour(r):
    kind = r.choice(["circle", "ellipse", "polygon", "star", "rose", "spline"])
    radius = r.uniform(15, 75)
    if kind == "circle":
        return f'type = "circle"\nradius = {radius:.2f}'
    if kind == "ellipse":
        return f'type = "ellipse"\nrx = {radius:.2f}\nry = {radius * r.uniform(0.3, 1):.2f}'
    if kind == "polygon":
        return (f'type = "polygon"\nsides = {r.randint(3, 9)}\nradius = {radius:.2f}\n'
                f'corner_radius = {r.uniform(0, radius / 3):.2f}')
    if kind == "star":
        return (f'type = "star"\npoints = {r.randint(3, 12)}\nouter_radius = {radius:.2f}\n'
                f'inner_radius = {radius * r.uniform(0.3, 0.95):.2f}')
    if kind == "rose":
        return (f'type = "rose"\nradius = {radius:.2f}\n'
                f'amplitude = {radius * r.uniform(0, 0.4):.2f}\npetals = {r.randint(2, 12)}')
    # A spline through points around the centre, in order of angle.
    k = r.randint(3, 8)
    points = []
    for i in range(k):
        a = 2 * math.pi * i / k + r.uniform(-0.3, 0.3)
        rr = radius * r.uniform(0.4, 1.0)
        points.append(f"[{rr * math.cos(a):.2f}, {rr * math.sin(a):.2f}]")
    return f'type = "spline"\npoints = [{", ".join(points)}]'


def design(seed):
    r = random.Random(seed)
    lines = ["version = 1", f'name = "random {seed}"', "[printer]",
             f"layer_height = {r.choice([0.5, 0.8, 1.0])}",
             "[shape]", f"height = {r.uniform(20, 150):.1f}",
             f"samples = {r.choice([60, 120, 200, 360])}", f"base_layers = {r.randint(0, 3)}"]
    if r.random() < 0.3:
        lines.append("walls = 2")
    lines += ["[shape.lower]", contour(r), "[shape.upper]", contour(r)]
    for _ in range(r.randint(0, 2)):
        inner = sorted([[round(r.uniform(0.05, 0.95), 2), round(r.uniform(-15, 25), 1)]
                        for _ in range(r.randint(1, 3))])
        lines += ["[[control.vertical]]", "points = " + str([[0.0, 0.0]] + inner + [[1.0, 0.0]])]
        if r.random() < 0.5:
            lines.append(f"angle = {r.uniform(0, 360):.1f}\nwidth = {r.uniform(20, 120):.1f}")
    if r.random() < 0.3:
        lines += ["[[control.horizontal]]", f"at = {r.choice([1.0, 0.5, 0.8])}",
                  f"reach = {r.uniform(0.05, 0.3):.2f}",
                  f"points = [[0.0, 0.0], [90.0, {r.uniform(-5, 8):.1f}], [180.0, 0.0], "
                  f"[270.0, {r.uniform(-5, 8):.1f}]]"]
    if r.random() < 0.6:
        lines += ["[texture]", f'combine = "{r.choice(["product", "sum"])}"']
        for axis in r.sample(["x", "y"], r.randint(1, 2)):
            wave = r.choice(["sine", "triangle", "square"])
            lines.append(f'{axis} = {{ wave = "{wave}", period = {r.randint(2, 30)}, '
                         f'amplitude = {r.uniform(0.2, 3):.2f} }}')
    if r.random() < 0.2:
        lines += ["[constraints]", "enforce = false"]
    return "\n".join(lines) + "\n"


if __name__ == "__main__":
    if len(sys.argv) != 4:
        sys.exit(__doc__)
    out, first, end = sys.argv[1], int(sys.argv[2]), int(sys.argv[3])
    os.makedirs(out, exist_ok=True)
    for seed in range(first, end):
        with open(os.path.join(out, f"r{seed}.toml"), "w") as f:
            f.write(design(seed))
