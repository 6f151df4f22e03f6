#!/usr/bin/env python3
"""Renders pbrt-v4's `nanovdb` medium against the same grid written as a `uniformgrid` (issue #15).

The fixture `crates/io/tests/data/nanovdb/rim.nvdb` (written by scripts/nanovdb-fixture.cpp with
the NanoVDB library) holds the voxels -3..12 x -2..9 x 0..13 under a rotated map, 0 on the
outer layer. pbrt-v4 clips a NanoVDB medium to the grid's world box; with a zero outer layer
that clipping cuts nothing, so a `uniformgrid` of the same voxels (placed by the grid's map as
a pbrt `Transform`) is the same medium (crates/io/tests/nanovdb.rs,
`the_world_box_clips_the_medium_as_in_pbrt`, checks that on 4000 points). This script writes
both scenes (the medium inside an index-matched sphere, a distant and an environment light, a
floor), renders each with `pt` for several seeds and runs `vcm compare`'s per-pixel Z-test on
each pair: the whole path (reader, placement, majorants, delta and ratio tracking) must give
the same image within the noise.

Usage (from the repository root, release binary built):

    scripts/nanovdb-render-check.py [--iterations 2048] [--seeds 2] [--vcm target/release/vcm]

Exits 1 when a Z-test fails. Python 3 standard library only.
"""

import argparse
import math
import os
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
FIXTURE = os.path.join(ROOT, "crates", "io", "tests", "data", "nanovdb", "rim.nvdb")

# The fixture's voxel box and values (scripts/nanovdb-fixture.cpp, rim()).
RIM_LO, RIM_HI = (-3, -2, 0), (12, 9, 13)


def rim(c):
    if any(c[a] <= RIM_LO[a] or c[a] >= RIM_HI[a] for a in range(3)):
        return 0.0
    return (3 * (c[0] - RIM_LO[0]) + 5 * (c[1] - RIM_LO[1]) + 7 * (c[2] - RIM_LO[2])) / 64.0


def ramp_map():
    """The fixture's index-to-world map: 0.05 * Rz(30 deg) * Rx(20 deg), then (0.3, -0.2, 0.5)."""
    a, b, s = math.radians(30), math.radians(20), 0.05
    rz = [[math.cos(a), -math.sin(a), 0], [math.sin(a), math.cos(a), 0], [0, 0, 1]]
    rx = [[1, 0, 0], [0, math.cos(b), -math.sin(b)], [0, math.sin(b), math.cos(b)]]
    m = [[s * sum(rz[i][k] * rx[k][j] for k in range(3)) for j in range(3)] for i in range(3)]
    return m, (0.3, -0.2, 0.5)


HEADER = """LookAt 0.5 -2.5 0.9  0.48 0 0.9  0 0 1
Camera "perspective" "float fov" 40
Film "rgb" "integer xresolution" 96 "integer yresolution" 64 "string filename" "x.exr"
Integrator "volpath" "integer maxdepth" 20
WorldBegin
"""

WORLD = """LightSource "distant" "point3 from" [1 -1 3] "point3 to" [0 0 0] "rgb L" [3 3 3]
LightSource "infinite" "rgb L" [0.2 0.2 0.25]
AttributeBegin
  Material "diffuse" "rgb reflectance" [0.5 0.5 0.5]
  Shape "trianglemesh" "point3 P" [-5 -5 -0.2  5 -5 -0.2  5 5 -0.2  -5 5 -0.2] "integer indices" [0 1 2 0 2 3]
AttributeEnd
AttributeBegin
  MediumInterface "m" ""
  Material "interface"
  Translate 0.48 -0.02 0.9
  Shape "sphere" "float radius" 0.85
AttributeEnd
"""

COEFFICIENTS = '"float sigma_a" 1 "float sigma_s" 8'


def scenes(folder):
    """Writes nano.pbrt and uniform.pbrt (and the fixture) into folder; returns their paths."""
    with open(FIXTURE, "rb") as source, open(os.path.join(folder, "rim.nvdb"), "wb") as copy:
        copy.write(source.read())
    nano = f'MakeNamedMedium "m" "string type" "nanovdb" "string filename" "rim.nvdb" {COEFFICIENTS}\n'
    # Two zero layers around the box; voxel i at index point i: the box from lo - 1/2.
    lo = [RIM_LO[a] - 2 for a in range(3)]
    n = [RIM_HI[a] - RIM_LO[a] + 5 for a in range(3)]
    density = " ".join(repr(rim((lo[0] + i, lo[1] + j, lo[2] + k)))
                       for k in range(n[2]) for j in range(n[1]) for i in range(n[0]))
    m, t = ramp_map()
    columns = [m[0][0], m[1][0], m[2][0], 0, m[0][1], m[1][1], m[2][1], 0, m[0][2], m[1][2], m[2][2], 0,
               t[0], t[1], t[2], 1]
    p0 = [x - 0.5 for x in lo]
    p1 = [p0[a] + n[a] for a in range(3)]
    uniform = ("AttributeBegin\n"
               f"Transform [{' '.join(repr(x) for x in columns)}]\n"
               f'MakeNamedMedium "m" "string type" "uniformgrid" "integer nx" {n[0]} "integer ny" {n[1]} '
               f'"integer nz" {n[2]} "point3 p0" [{p0[0]} {p0[1]} {p0[2]}] "point3 p1" [{p1[0]} {p1[1]} {p1[2]}] '
               f'"float density" [{density}] {COEFFICIENTS}\n'
               "AttributeEnd\n")
    paths = []
    for name, medium in (("nano", nano), ("uniform", uniform)):
        path = os.path.join(folder, f"{name}.pbrt")
        with open(path, "w") as out:
            out.write(HEADER + medium + WORLD)
        paths.append(path)
    return paths


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--vcm", default=os.path.join(ROOT, "target", "release", "vcm"))
    parser.add_argument("--iterations", type=int, default=2048)
    parser.add_argument("--seeds", type=int, default=2)
    args = parser.parse_args()
    if not os.path.exists(args.vcm):
        sys.exit(f"{args.vcm} is missing: cargo build --release")
    failed = 0
    with tempfile.TemporaryDirectory() as folder:
        nano, uniform = scenes(folder)
        for seed in range(1, args.seeds + 1):
            images = []
            for scene in (nano, uniform):
                stem = os.path.splitext(scene)[0] + f"-{seed}"
                subprocess.run([args.vcm, "render", "--scene", scene, "-a", "pt", "-i", str(args.iterations),
                                "--seed", str(seed), "--quiet", "-o", stem + ".exr", "--variance", stem + "-var.exr"],
                               check=True)
                images.append(stem)
            result = subprocess.run([args.vcm, "compare", images[0] + ".exr", images[1] + ".exr",
                                     "--variance-a", images[0] + "-var.exr", "--variance-b", images[1] + "-var.exr"],
                                    capture_output=True, text=True)
            lines = [line for line in result.stdout.splitlines() if line.startswith(("R ", "per-pixel"))]
            print(f"seed {seed}, {args.iterations} iterations, nanovdb vs uniformgrid:")
            for line in lines:
                print("  " + line)
            failed += int(result.returncode != 0 or not any("PASSED" in line for line in lines))
    sys.exit(1 if failed else 0)


if __name__ == "__main__":
    main()
