#!/usr/bin/env python3
"""Writes a Mitsuba 3 scene with a ~1M-triangle mesh, for ray-casting benchmarks on large meshes.

The mesh is the noisy tessellated sphere of `crates/scene/examples/bvh_bench.rs` in spirit (its
own vertices: radius 1 ± 0.5 %, `stacks` × 2·`stacks` quads, fixed seed), stored as binary PLY,
over a 10 × 10 ground rectangle, under a constant environment. Used by
`scripts/accel-history.sh` (docs/bvh.md, "Against the renderer of the issue's date").

Usage: scripts/big-mesh-scene.py OUT_DIR [STACKS]   (default 500 stacks: 998,000 triangles)
"""
import math
import random
import struct
import sys
from pathlib import Path


def main():
    if len(sys.argv) not in (2, 3):
        sys.exit(__doc__)
    out = Path(sys.argv[1])
    stacks = int(sys.argv[2]) if len(sys.argv) == 3 else 500
    if stacks < 2:
        sys.exit("error: STACKS must be at least 2")
    slices = 2 * stacks
    rng = random.Random(1)
    vertices = []
    for i in range(stacks + 1):
        theta = math.pi * i / stacks
        for j in range(slices):
            phi = 2 * math.pi * j / slices
            r = 1.0 + 0.01 * (rng.random() - 0.5)
            vertices.append((r * math.sin(theta) * math.cos(phi), r * math.cos(theta), r * math.sin(theta) * math.sin(phi)))
    triangles = []
    for i in range(stacks):
        for j in range(slices):
            a, b = i * slices + j, i * slices + (j + 1) % slices
            c, d = (i + 1) * slices + j, (i + 1) * slices + (j + 1) % slices
            # The pole rows' quads degenerate to one triangle each.
            if i > 0:
                triangles.append((a, b, c))
            if i < stacks - 1:
                triangles.append((b, d, c))
    out.mkdir(parents=True, exist_ok=True)
    header = (
        "ply\nformat binary_little_endian 1.0\n"
        f"element vertex {len(vertices)}\nproperty float x\nproperty float y\nproperty float z\n"
        f"element face {len(triangles)}\nproperty list uchar int vertex_indices\nend_header\n"
    )
    with open(out / "sphere.ply", "wb") as f:
        f.write(header.encode())
        f.write(b"".join(struct.pack("<3f", *v) for v in vertices))
        f.write(b"".join(struct.pack("<B3i", 3, *t) for t in triangles))
    (out / "big-mesh.xml").write_text(
        """<scene version="3.0.0">
    <integrator type="path"/>
    <sensor type="perspective">
        <float name="fov" value="40"/>
        <transform name="to_world"><lookat origin="0, 0.5, 4" target="0, 0, 0" up="0, 1, 0"/></transform>
        <film type="hdrfilm"><integer name="width" value="256"/><integer name="height" value="256"/></film>
    </sensor>
    <bsdf type="diffuse" id="grey"><rgb name="reflectance" value="0.6"/></bsdf>
    <shape type="ply"><string name="filename" value="sphere.ply"/><ref id="grey"/></shape>
    <shape type="rectangle">
        <transform name="to_world"><scale value="5"/><rotate x="1" angle="-90"/><translate y="-1.2"/></transform>
        <ref id="grey"/>
    </shape>
    <emitter type="constant"><rgb name="radiance" value="1"/></emitter>
</scene>
"""
    )
    print(f"{out / 'big-mesh.xml'}: {len(vertices)} vertices, {len(triangles)} triangles")


if __name__ == "__main__":
    main()
