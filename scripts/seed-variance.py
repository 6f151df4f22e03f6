#!/usr/bin/env python3
"""Per-pixel variance at equal samples of two settings of our renderer, across seeds.

Renders SCENE SEEDS times with `vcm render -a ALGORITHM -i SPP -r RESOLUTION --seed s` plus the
arguments of each setting (--a and --b, e.g. --b "--mis-compensation off"), and prints for each
the relative variance Σ_pixels,channels var / Σ mean² (the variance across the seeds, unbiased),
the image mean with its standard error over the seeds, and the ratio A / B. Counts only, no
timing: the estimators' noise per sample (time is measured by scripts/paired-bench.sh).

Run from the repository root after `cargo build --release`, with a Python that has numpy
(scripts/peer-bench.py creates one in target/peer-bench/venv):

    target/peer-bench/venv/bin/python scripts/seed-variance.py \\
        ../shared/scenes/mitsuba/matpreview/matpreview.xml -a vcm --b "--mis-compensation off"
"""

import argparse
import os
import shlex
import subprocess
import tempfile

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def read_pfm(path):
    """A PFM image as a float array (height, width, 3)."""
    with open(path, "rb") as f:
        kind = f.readline().strip()
        width, height = map(int, f.readline().split())
        scale = float(f.readline())
        data = np.frombuffer(f.read(), dtype="<f4" if scale < 0 else ">f4")
    channels = 3 if kind == b"PF" else 1
    image = data.reshape(height, width, channels).astype(np.float64)
    return image if channels == 3 else np.repeat(image, 3, axis=2)


def measure(args, extra, out_dir):
    """(relative variance, mean of the image means, its standard error) of one setting."""
    images = []
    for seed in range(args.seeds):
        out = os.path.join(out_dir, "image.pfm")
        command = [args.vcm, "render", "--scene", args.scene, "-a", args.algorithm, "-i", str(args.spp),
                   "-r", args.resolution, "--seed", str(seed), "--quiet", "-o", out, *shlex.split(extra)]
        subprocess.run(command, check=True, capture_output=True)
        images.append(read_pfm(out))
    images = np.array(images)
    mean, var = images.mean(axis=0), images.var(axis=0, ddof=1)
    means = images.mean(axis=(1, 2, 3))
    return var.sum() / max((mean ** 2).sum(), 1e-300), means.mean(), means.std(ddof=1) / np.sqrt(args.seeds)


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("scene")
    parser.add_argument("-a", "--algorithm", default="vcm")
    parser.add_argument("--spp", type=int, default=4)
    parser.add_argument("--seeds", type=int, default=8)
    parser.add_argument("--resolution", default="171x128")
    parser.add_argument("--a", dest="setting_a", default="", help="arguments of setting A (default: none)")
    parser.add_argument("--b", dest="setting_b", default="", help="arguments of setting B")
    parser.add_argument("--vcm", default=os.path.join(ROOT, "target", "release", "vcm"))
    args = parser.parse_args()
    if args.seeds < 2:
        parser.error("--seeds must be at least 2")
    results = {}
    with tempfile.TemporaryDirectory() as out_dir:
        for name, extra in (("A", args.setting_a), ("B", args.setting_b)):
            rel, mean, error = measure(args, extra, out_dir)
            results[name] = rel
            print(f"{name} ({extra or 'defaults'}): relative variance {rel:.5g}, mean {mean:.5f} ± {error:.5f}")
    print(f"A / B: {results['A'] / results['B']:.3f}")


if __name__ == "__main__":
    main()
