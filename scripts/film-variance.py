#!/usr/bin/env python3
"""Per-pixel variance at equal sample counts, `--film fis` against `--film splat`, on a scene file.

For each reconstruction filter (the file's own `<rfilter>` replaced by box, tent and gaussian in
a temporary copy, so the file must not reference other files by relative path), renders
the scene with both film modes and the same seed and iteration count, writes the per-pixel
variance of the mean (`--variance`, PFM) and prints the mean over pixels and channels and the
ratio fis/splat. Counts only (no timing). Python 3 standard library only.

Usage (from the repository root, after `cargo build --release`):

    scripts/film-variance.py /work/shared/scenes/mitsuba/cornell-box/cornell_box.xml \\
        --resolution 128x128 --iterations 64 --algorithm pt
"""

import argparse
import os
import re
import struct
import subprocess
import sys
import tempfile

FILTERS = {
    "box": '<rfilter type="box"/>',
    "tent r=1": '<rfilter type="tent"/>',
    "gaussian σ=0.5 r=2": '<rfilter type="gaussian"/>',
}


def read_pfm(path):
    """Returns the float values of a PFM file (any channel count)."""
    with open(path, "rb") as f:
        kind = f.readline().strip()
        if kind not in (b"PF", b"Pf"):
            sys.exit(f"{path}: not a PFM file")
        width, height = map(int, f.readline().split())
        scale = float(f.readline())
        channels = 3 if kind == b"PF" else 1
        data = f.read()
    endian = "<" if scale < 0 else ">"
    count = width * height * channels
    return struct.unpack(f"{endian}{count}f", data[: 4 * count])


def mean_variance(binary, scene, film, args, directory):
    variance = os.path.join(directory, f"variance-{film}.pfm")
    image = os.path.join(directory, f"image-{film}.pfm")
    command = [binary, "render", "--scene", scene, "--film", film, "-a", args.algorithm,
               "--iterations", str(args.iterations), "--resolution", args.resolution,
               "--seed", "1", "--quiet", "-o", image, "--variance", variance]
    subprocess.run(command, check=True, stdout=subprocess.DEVNULL)
    values = read_pfm(variance)
    return sum(values) / len(values)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("scene")
    parser.add_argument("--resolution", default="128x128")
    parser.add_argument("--iterations", type=int, default=64)
    parser.add_argument("--algorithm", default="pt")
    parser.add_argument("--binary", default="target/release/vcm")
    args = parser.parse_args()
    with open(args.scene) as f:
        text = f.read()
    if not re.search(r"<rfilter[^>]*/>", text):
        sys.exit(f"{args.scene}: expected a self-closing <rfilter .../> to replace")
    with tempfile.TemporaryDirectory() as directory:
        for name, rfilter in FILTERS.items():
            copy = os.path.join(directory, "scene.xml")
            with open(copy, "w") as f:
                f.write(re.sub(r"<rfilter[^>]*/>", rfilter, text))
            fis = mean_variance(args.binary, copy, "fis", args, directory)
            splat = mean_variance(args.binary, copy, "splat", args, directory)
            print(f"{name}: mean variance fis {fis:.4e}, splat {splat:.4e}, fis/splat {fis / splat:.3f}")


if __name__ == "__main__":
    main()
