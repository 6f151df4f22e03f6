#!/usr/bin/env python3
"""The conformance verdict of a render against a Mitsuba 3 suite reference, and the same verdict
for Mitsuba's own path tracer at the same sample count: is a failure ours, or the estimator's at
that budget?

`judge IMAGE VARIANCE REFERENCE` applies the rule of `vcm conformance` (docs/conformance.md:
z = (a − b)/sqrt(var_a + var_b), the reference's per-sample variance floored at 1e-4 and divided
by 32000, Šidák level over all pixel channels at α = 0.01) and prints the passing fraction, the
channel mean ratios, the relative standard error of the image mean (from the variance image),
and per 32-column band the failing fraction. IMAGE/VARIANCE: e.g. `vcm render --variance` EXRs.

`mitsuba SCENE N OUT [--integrator volpath]` renders SCENE with Mitsuba's `path` (or the given) integrator as N independent 1-spp
iterations (seeds SEED·100000 + i) and writes OUT.exr (mean) and OUT_var.exr (variance of the
mean from the spread of the iterations, as `vcm render --variance` estimates it).

Needs Mitsuba 3 and numpy (e.g. /work/scratch/mienv/bin/python). Counts only, no timing.

    scripts/mitsuba-pass-rate.py mitsuba SUITE/various_emitters/test_various_emitters_ptracer.xml 61 /tmp/m61
    scripts/mitsuba-pass-rate.py judge /tmp/m61.exr /tmp/m61_var.exr \\
        SUITE/various_emitters/refs/test_various_emitters_ref_rgb.exr
"""

import argparse
import math

import mitsuba as mi
import numpy as np

mi.set_variant("scalar_rgb")


def read(path):
    return np.array(mi.Bitmap(path)).astype(np.float64)[..., :3]


def sidak_threshold(entries, alpha=0.01):
    """|z| above which a two-sided Z-test fails at the Šidák level over `entries` tests."""
    level = 1.0 - (1.0 - alpha) ** (1.0 / entries)
    lo, hi = 0.0, 40.0
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        if math.erfc(mid / math.sqrt(2.0)) > level:
            lo = mid
        else:
            hi = mid
    return lo


def judge(args):
    a, var_a = read(args.image), read(args.variance)
    ref = read(args.reference)
    var_ref = np.maximum(read(args.reference.replace(".exr", "_var.exr")), 1e-4) / args.reference_spp
    z = (a - ref) / np.sqrt(var_a + var_ref)
    fail = np.abs(z) > sidak_threshold(z.size)
    pixels = a.shape[0] * a.shape[1]
    mean, mean_ref = a.reshape(-1, 3).mean(0), ref.reshape(-1, 3).mean(0)
    standard_error = np.sqrt(var_a.reshape(-1, 3).sum(0)) / pixels
    print(f"pass {100 * (1 - fail.mean()):.2f} %  mean ratio {np.round(mean / mean_ref, 4)}"
          f"  relative standard error of the mean {np.round(standard_error / mean, 4)}")
    for x in range(0, a.shape[1], 32):
        band = (slice(None), slice(x, x + 32))
        print(f"  columns {x:4d}-{x + 31:4d}: fail {100 * fail[band].mean():6.2f} %  mean z {z[band].mean():+.2f}")


def mitsuba(args):
    scene = mi.load_file(args.scene, integrator=args.integrator, spp=1)
    total = total_squares = 0.0
    for i in range(args.iterations):
        image = np.array(mi.render(scene, seed=args.seed * 100000 + i, spp=1)).astype(np.float64)[..., :3]
        total = total + image
        total_squares = total_squares + image * image
    n = args.iterations
    mean = total / n
    variance_of_mean = (total_squares / n - mean * mean) / (n - 1)
    mi.Bitmap(mean.astype(np.float32)).write(args.out + ".exr")
    mi.Bitmap(variance_of_mean.astype(np.float32)).write(args.out + "_var.exr")


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    commands = parser.add_subparsers(dest="command", required=True)
    j = commands.add_parser("judge")
    j.add_argument("image")
    j.add_argument("variance")
    j.add_argument("reference", help="the suite's refs/<name>_ref_rgb.exr (its _var.exr beside it)")
    j.add_argument("--reference-spp", type=float, default=32000.0)
    m = commands.add_parser("mitsuba")
    m.add_argument("scene")
    m.add_argument("iterations", type=int)
    m.add_argument("out", help="output prefix")
    m.add_argument("--seed", type=int, default=1)
    m.add_argument("--integrator", default="path", help="the scene's `integrator` parameter: volpath for media scenes")
    args = parser.parse_args()
    judge(args) if args.command == "judge" else mitsuba(args)


if __name__ == "__main__":
    main()
