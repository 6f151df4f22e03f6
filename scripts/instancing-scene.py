#!/usr/bin/env python3
"""Generates the instancing memory benchmark of docs/instancing.md into a directory (default
/tmp/vcm-instancing):

- mesh.ply: a bumpy sphere of 2 * N * N triangles (N = 224: 100,352 triangles), binary PLY;
- instanced.xml: a Mitsuba 3 scene with COUNT instances (default 10,000) of one shapegroup
  holding the mesh, on a square grid, each turned about z and scaled;
- flat-K.xml for each K in --flat (default 1 10 100): the first K placements as separate
  shapes (the mesh loaded and transformed K times), for comparison.

Usage: scripts/instancing-scene.py [--dir DIR] [--count COUNT] [--grid N] [--flat K ...]
Then measure, e.g.:
  /usr/bin/time -v target/release/vcm render --scene DIR/instanced.xml -a pt -i 1 -o /tmp/i.exr
(the "Maximum resident set size" line).
"""

import argparse
import math
import os
import random
import struct


def write_mesh(path, n):
    """A sphere of radius ~1 with a bump pattern, (n + 1) * (n + 1) vertices, 2 n^2 triangles."""
    vertices = []
    for i in range(n + 1):
        theta = math.pi * i / n
        for j in range(n + 1):
            phi = 2.0 * math.pi * j / n
            r = 1.0 + 0.05 * math.sin(7.0 * theta) * math.cos(9.0 * phi)
            vertices.append((r * math.sin(theta) * math.cos(phi), r * math.sin(theta) * math.sin(phi), r * math.cos(theta)))
    faces = []
    for i in range(n):
        for j in range(n):
            a = i * (n + 1) + j
            b = a + n + 1
            faces.append((a, b, a + 1))
            faces.append((a + 1, b, b + 1))
    header = (
        "ply\nformat binary_little_endian 1.0\n"
        f"element vertex {len(vertices)}\nproperty float x\nproperty float y\nproperty float z\n"
        f"element face {len(faces)}\nproperty list uchar int vertex_indices\nend_header\n"
    )
    with open(path, "wb") as f:
        f.write(header.encode("ascii"))
        f.write(b"".join(struct.pack("<3f", *v) for v in vertices))
        f.write(b"".join(struct.pack("<B3i", 3, *t) for t in faces))
    return len(faces)


def placements(count):
    """(x, y, angle in degrees, scale) of each instance on a square grid of spacing 3."""
    rng = random.Random(1)
    side = math.ceil(math.sqrt(count))
    for k in range(count):
        x, y = 3.0 * (k % side - side / 2), 3.0 * (k // side - side / 2)
        yield x, y, rng.uniform(0.0, 360.0), rng.uniform(0.5, 1.0)


def header(extent):
    return f"""<scene version="3.0.0">
    <integrator type="path"><integer name="max_depth" value="3"/></integrator>
    <sensor type="perspective">
        <float name="fov" value="60"/>
        <transform name="to_world"><lookat origin="0, {-extent}, {extent}" target="0, 0, 0" up="0, 0, 1"/></transform>
        <film type="hdrfilm"><integer name="width" value="256"/><integer name="height" value="256"/></film>
    </sensor>
    <emitter type="constant"><rgb name="radiance" value="1, 1, 1"/></emitter>
    <bsdf type="diffuse" id="grey"><rgb name="reflectance" value="0.5, 0.5, 0.5"/></bsdf>
"""


def transform(x, y, angle, scale):
    return f'<transform name="to_world"><scale value="{scale:.4f}"/><rotate z="1" angle="{angle:.3f}"/><translate x="{x}" y="{y}"/></transform>'


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--dir", default="/tmp/vcm-instancing")
    parser.add_argument("--count", type=int, default=10000)
    parser.add_argument("--grid", type=int, default=224)
    parser.add_argument("--flat", type=int, nargs="*", default=[1, 10, 100])
    args = parser.parse_args()
    os.makedirs(args.dir, exist_ok=True)
    triangles = write_mesh(os.path.join(args.dir, "mesh.ply"), args.grid)
    places = list(placements(args.count))
    extent = 1.5 * math.sqrt(args.count) + 3.0
    with open(os.path.join(args.dir, "instanced.xml"), "w") as f:
        f.write(header(extent))
        f.write('    <shape type="shapegroup" id="mesh"><shape type="ply"><string name="filename" value="mesh.ply"/><ref id="grey"/></shape></shape>\n')
        for p in places:
            f.write(f'    <shape type="instance"><ref id="mesh"/>{transform(*p)}</shape>\n')
        f.write("</scene>\n")
    for k in args.flat:
        with open(os.path.join(args.dir, f"flat-{k}.xml"), "w") as f:
            f.write(header(extent))
            for p in places[:k]:
                f.write(f'    <shape type="ply"><string name="filename" value="mesh.ply"/><ref id="grey"/>{transform(*p)}</shape>\n')
            f.write("</scene>\n")
    print(f"{args.dir}: mesh.ply ({triangles} triangles), instanced.xml ({args.count} instances), flat-K.xml for K in {args.flat}")


if __name__ == "__main__":
    main()
