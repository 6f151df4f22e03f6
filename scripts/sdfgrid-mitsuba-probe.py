#!/usr/bin/env python3
"""Prints Mitsuba 3's hits on its own unit-test sdfgrid (the diagonal plane y + z = 1 on a 2x2x2
grid, x fastest): distance, geometric normal and shading normal for both `normals` modes.

The `smooth` shading normals it prints are the oracle values of
crates/io/src/sdfgrid/tests.rs::mitsubas_diagonal_plane. Needs the `mitsuba` package (3.9.1 was
used) with its scalar_rgb variant: `python3 scripts/sdfgrid-mitsuba-probe.py`.
"""
import math

import mitsuba as mi

mi.set_variant("scalar_rgb")
s = math.sqrt(0.5)
grid = mi.TensorXf([-s, -s, 0, 0, 0, 0, s, s], shape=(2, 2, 2, 1))
for mode in ["smooth", "analytic"]:
    scene = mi.load_dict({"type": "scene", "sdf": {"type": "sdfgrid", "grid": grid, "normals": mode}})
    for y in [0.1, 0.6, 0.9]:
        si = scene.ray_intersect(mi.Ray3f(o=[0.3, y, 3], d=[0, 0, -1]))
        print(f"{mode:8} hit at {si.p}: t {si.t:.6f}, n {si.n}, shading n {si.sh_frame.n}")
