#!/usr/bin/env python3
"""CPU time per iteration of spectral against RGB VCM (issue #11's equal-time ratio).

Runs `vcm render --scene S -a vcm -i N -r RxR` and the same with `--spectral` as PAIRS
interleaved pairs (RGB first, then spectral, alternating so that drifts of a shared machine
hit both alike) and prints the user+system CPU time of each mode summed over the pairs, and
their ratio. The relMSE ratio at equal *iterations* (docs/spectral.md) times this cost ratio is
the relMSE ratio at equal time. Run it on a quiet machine.

    scripts/spectral-cost.py [--vcm target/release/vcm] [--scene 1] [--iterations 64]
                             [--resolution 128] [--pairs 5]
"""

import argparse
import os
import resource
import subprocess
import tempfile


def cpu_of(command):
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    subprocess.run(command, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--vcm", default="target/release/vcm")
    parser.add_argument("--scene", default="1")
    parser.add_argument("--iterations", type=int, default=64)
    parser.add_argument("--resolution", type=int, default=128)
    parser.add_argument("--pairs", type=int, default=5)
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as out:
        base = [args.vcm, "render", "--scene", args.scene, "-a", "vcm", "-i", str(args.iterations),
                "-r", f"{args.resolution}x{args.resolution}", "-o", os.path.join(out, "x.exr")]
        cpu = {"rgb": 0.0, "spectral": 0.0}
        for pair in range(args.pairs):
            rgb = cpu_of(base)
            spectral = cpu_of(base + ["--spectral"])
            cpu["rgb"] += rgb
            cpu["spectral"] += spectral
            print(f"pair {pair + 1}: rgb {rgb:.2f} s, spectral {spectral:.2f} s CPU")
    print(f"total CPU: rgb {cpu['rgb']:.2f} s, spectral {cpu['spectral']:.2f} s, "
          f"ratio spectral/rgb {cpu['spectral'] / cpu['rgb']:.4f}")


if __name__ == "__main__":
    main()
