#!/usr/bin/env python3
"""Writes scenes/hair-curves.txt, the curve file of scenes/hair.xml: a tuft of 160 hairs
growing from a disc of radius 0.35 at the origin, each a uniform cubic B-spline of 6 control
points ("x y z radius" per line, an empty line between curves: the format of io::curves)
that rises, leans outwards and droops. Deterministic (seeded); run from the repository root."""
import math
import random

random.seed(14)
lines = []
for _ in range(160):
    r = 0.35 * math.sqrt(random.random())
    a = 2 * math.pi * random.random()
    x0, z0 = r * math.cos(a), r * math.sin(a)
    lean = 0.25 + 0.5 * random.random()
    height = 0.9 + 0.4 * random.random()
    dx, dz = math.cos(a) * lean, math.sin(a) * lean
    for k in range(6):
        t = k / 5
        # Up first, then outwards and down (a droop quadratic in t).
        y = height * (t - 0.55 * t * t)
        x = x0 + dx * t * t + 0.03 * random.uniform(-1, 1)
        z = z0 + dz * t * t + 0.03 * random.uniform(-1, 1)
        radius = 0.008 * (1 - 0.6 * t)
        lines.append(f"{x:.5f} {y:.5f} {z:.5f} {radius:.5f}")
    lines.append("")
with open("scenes/hair-curves.txt", "w") as f:
    f.write("\n".join(lines))
