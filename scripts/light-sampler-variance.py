#!/usr/bin/env python3
"""Path tracer variance with the light tree against the power selection, at equal samples.

For each scene: `vcm render -a pt --light-sampler tree|power --variance FILE.pfm` with the same
iterations and seed, then the ratio of the mean per-pixel variance of the mean (tree / power,
averaged over pixels and channels) and the share of pixels whose variance the tree lowers.
Usage: light-sampler-variance.py VCM_BINARY ITERATIONS SCENE... (built-in ids or files).
"""
import os
import struct
import subprocess
import sys
import tempfile


def read_pfm(path):
    with open(path, "rb") as f:
        kind = f.readline().strip()
        width, height = map(int, f.readline().split())
        scale = float(f.readline())
        channels = 3 if kind == b"PF" else 1
        endian = "<" if scale < 0 else ">"
        count = width * height * channels
        values = struct.unpack(f"{endian}{count}f", f.read(4 * count))
    return values


def main():
    vcm, iterations, scenes = sys.argv[1], sys.argv[2], sys.argv[3:]
    tmp = tempfile.mkdtemp()
    for scene in scenes:
        variances = {}
        for sampler in ("tree", "power"):
            out = os.path.join(tmp, f"{sampler}.pfm")
            var = os.path.join(tmp, f"{sampler}-var.pfm")
            subprocess.run([vcm, "render", "--scene", scene, "-a", "pt", "-i", iterations, "--seed", "1",
                            "--light-sampler", sampler, "-o", out, "--variance", var, "--quiet"], check=True,
                           stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
            variances[sampler] = read_pfm(var)
        tree, power = variances["tree"], variances["power"]
        ratio = sum(tree) / sum(power) if sum(power) > 0 else float("nan")
        pixels = [(tree[i:i + 3], power[i:i + 3]) for i in range(0, len(tree), 3)]
        lower = sum(1 for t, p in pixels if sum(t) < sum(p))
        higher = sum(1 for t, p in pixels if sum(t) > sum(p))
        print(f"{scene}: {iterations} spp, mean variance tree/power = {ratio:.3f}; "
              f"pixels lower {lower}, higher {higher}, equal {len(pixels) - lower - higher}")


main()
