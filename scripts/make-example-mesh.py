#!/usr/bin/env python3
"""Writes assets/meshes/lobed-vase.stl: a closed, solid vase of revolution with six soft lobes,
as a modelling program would export it (binary STL, millimetres, z up). The example of SPEC §15:
`clayloft assets/meshes/lobed-vase.stl`. Standard library only."""
import math
import struct
import sys

N, RINGS, H = 96, 61, 90.0


def radius(z, a):
    t = z / H
    return 30.0 + 7.0 * math.sin(math.pi * t) - 4.0 * t + 1.6 * math.cos(6 * a) * (0.3 + t)


verts = []
for k in range(RINGS):
    z = H * k / (RINGS - 1)
    for i in range(N):
        a = 2 * math.pi * i / N
        r = radius(z, a)
        verts.append((r * math.cos(a), r * math.sin(a), z))
bottom, top = len(verts), len(verts) + 1
verts += [(0.0, 0.0, 0.0), (0.0, 0.0, H)]


def at(k, i):
    return k * N + i % N


tris = []
for k in range(RINGS - 1):
    for i in range(N):
        tris.append((at(k, i), at(k, i + 1), at(k + 1, i + 1)))
        tris.append((at(k, i), at(k + 1, i + 1), at(k + 1, i)))
for i in range(N):
    tris.append((bottom, at(0, i + 1), at(0, i)))
    tris.append((top, at(RINGS - 1, i), at(RINGS - 1, i + 1)))


def normal(a, b, c):
    u = [b[j] - a[j] for j in range(3)]
    v = [c[j] - a[j] for j in range(3)]
    n = (u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0])
    length = math.sqrt(sum(x * x for x in n)) or 1.0
    return tuple(x / length for x in n)


out = sys.argv[1] if len(sys.argv) > 1 else "assets/meshes/lobed-vase.stl"
with open(out, "wb") as f:
    f.write(b"lobed vase, Clayloft example mesh".ljust(80, b" "))
    f.write(struct.pack("<I", len(tris)))
    for t in tris:
        a, b, c = (verts[j] for j in t)
        f.write(struct.pack("<12fH", *normal(a, b, c), *a, *b, *c, 0))
print(f"wrote {out}: {len(tris)} triangles")
