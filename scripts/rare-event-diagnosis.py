#!/usr/bin/env python3
"""Why a render fails the conformance Z-test against a Mitsuba 3 suite reference: are the
failing pixel channels ones where the render saw no sample of a rare contribution?

    rare-event-diagnosis.py IMAGE VARIANCE SPP LONG LONG_VARIANCE LONG_SPP REFERENCE

IMAGE/VARIANCE: the render under test (`vcm render --variance`, SPP iterations); LONG/
LONG_VARIANCE: a much longer render of the same scene (LONG_SPP iterations, another seed), taken
as the truth of the per-sample statistics; REFERENCE: Mitsuba's `refs/<name>_ref_rgb.exr` (its
`_var.exr` beside it, per-sample variance of 32000 spp). The Z-test is `vcm conformance`'s
(reference variance floored at 1e-4, Šidák at α = 0.01). For failing and passing entries it
prints medians of: our per-sample variance / the reference's; the expected number of "events"
in SPP samples, SPP · mean² / per-sample variance (a contribution that comes as rare hits of
probability p has mean²/variance ≈ p); the render's own variance estimate / the long render's.
Counts only, no timing. Needs numpy and Mitsuba 3 (to read EXR), e.g. /work/scratch/mienv/bin/python.
"""

import math
import sys

import mitsuba as mi
import numpy as np

mi.set_variant("scalar_rgb")


def read(path):
    return np.array(mi.Bitmap(path)).astype(np.float64)[..., :3]


def sidak_threshold(entries, alpha=0.01):
    level = 1.0 - (1.0 - alpha) ** (1.0 / entries)
    lo, hi = 0.0, 40.0
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if math.erfc(mid / math.sqrt(2.0)) > level else (lo, mid)
    return lo


def main(image, variance, spp, long, long_variance, long_spp, reference):
    a, var_a, spp = read(image), read(variance), float(spp)
    t, var_t, long_spp = read(long), read(long_variance), float(long_spp)
    ref = read(reference)
    var_ref = read(reference.replace(".exr", "_var.exr"))
    z = (a - ref) / np.sqrt(var_a + np.maximum(var_ref, 1e-4) / 32000)
    fail = np.abs(z) > sidak_threshold(z.size)
    print(f"pass {100 * (1 - fail.mean()):.2f} %: {(fail & (z < 0)).sum()} failing entries below the "
          f"reference, {(fail & (z > 0)).sum()} above")
    per_sample = var_t * long_spp
    events = spp * t**2 / np.maximum(per_sample, 1e-30)
    for name, m in (("failing", fail), ("passing", ~fail)):
        print(f"{name}: median variance per sample ours/reference "
              f"{np.median(per_sample[m] / np.maximum(var_ref[m], 1e-30)):.2f}, expected events in {spp:.0f} spp "
              f"{np.median(events[m]):.2f}, own variance estimate / long render's "
              f"{np.median(var_a[m] * spp / np.maximum(per_sample[m], 1e-30)):.2f}")
    zt = (t - ref) / np.sqrt(var_t + np.maximum(var_ref, 1e-4) / 32000)
    print(f"long render: pass {100 * (1 - (np.abs(zt) > sidak_threshold(zt.size)).mean()):.2f} %")
    for x in range(0, a.shape[1], 64):
        band = (slice(None), slice(x, x + 64))
        print(f"  columns {x:4}-{x + 63:4}: fail {100 * fail[band].mean():5.2f} %, "
              f"expected events {np.median(events[band]):6.2f}")


if __name__ == "__main__":
    if len(sys.argv) != 8:
        sys.exit(__doc__)
    main(*sys.argv[1:])
