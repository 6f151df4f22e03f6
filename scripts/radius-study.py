#!/usr/bin/env python3
"""The price of VCM's radius modes above 512² at equal CPU time: bias and variance (issue #13).

Above 512² pixels the default `global` radius mode shrinks the merging radius by √(512² / pixels)
so that merging costs the same per pixel at every resolution (docs/performance.md, "VCM from
256² to 4096²"); `fixed` keeps the radius of 512², `per-pixel` ties it to each pixel's
footprint. A smaller radius has less kernel bias and more variance. This script measures both,
per built-in scene, at one resolution (default 1024²):

1. A reference: the mean of two `vcm` renders with seeds 1000 and 1001 (default 24 iterations
   each) in `global` mode with half the default radius factor, so that its kernel is smaller
   than every tested mode's; its own noise is estimated from the difference of the two halves.
2. The CPU time per iteration of each mode (a 2-iteration probe, user + system time of the
   process, which depends far less on other load than wall time).
3. For each mode, two renders (seeds 1 and 2) of as many iterations as fit in the same CPU
   budget (default 48 CPU-seconds), and:
   - relMSE: their mean relative MSE against the reference, mean((a − R)² / (R² + 0.01)), the
     metric of `vcm compare` and of the peers table;
   - variance: mean((a − b)² / 2 / (R² + 0.01)), the part of relMSE that is the render's noise;
   - bias² + reference noise: the rest, relMSE − variance, minus the reference's noise
     mean((r₁ − r₂)² / 4 / (R² + 0.01)), printed in the table's stamp line.
4. Writes the table between `<!-- perf-table:radius-study:begin -->` and
   `<!-- perf-table:radius-study:end -->` in docs/performance.md, stamped with date, commit,
   machine and commands.

Usage (from the repository root, after `cargo build --release`; about 40 CPU-minutes at the
defaults, which on 2 cores is 20 minutes of a quiet machine; the CPU-time budget keeps the
comparison fair on a busy one):

    scripts/radius-study.py
    scripts/radius-study.py --resolution 128x128 --reference-iterations 2 --budget 2 \\
        --scenes 1 --performance /tmp/performance.md   # a quick end-to-end check

Python 3 standard library only.
"""

import argparse
import array
import importlib.util
import os
import subprocess
import sys
import tempfile

# The stamp (date, commit, machine) and the marker replacement of scripts/perf-tables.py.
_spec = importlib.util.spec_from_file_location("perf_tables", os.path.join(os.path.dirname(__file__), "perf-tables.py"))
perf_tables = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(perf_tables)

MODES = ["global", "fixed", "per-pixel"]
SCENES = {0: "cornell-sun", 1: "cornell-area-mirror", 2: "cornell-point", 3: "cornell-env"}
EPSILON = 1e-2  # the relative MSE's ε (crates/image-metrics, RELATIVE_MSE_EPSILON)
DEFAULT_RADIUS_FACTOR = 0.003  # `vcm render --help`, --radius-factor


def fail(message):
    sys.exit(f"radius-study: {message}")


def render(vcm, scene, resolution, iterations, seed, mode, out, radius_factor=None):
    """Runs `vcm render` to a PFM file; returns the process's CPU seconds (user + system)."""
    command = [vcm, "render", "--scene", str(scene), "-a", "vcm", "-r", resolution, "-i", str(iterations),
               "--seed", str(seed), "--radius-mode", mode, "--quiet", "-o", out]
    if radius_factor is not None:
        command += ["--radius-factor", str(radius_factor)]
    print("+ " + " ".join(command), file=sys.stderr, flush=True)
    process = subprocess.Popen(command, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    _, status, usage = os.wait4(process.pid, 0)
    stderr = process.stderr.read()
    process.stderr.close()
    process.returncode = os.waitstatus_to_exitcode(status)
    if process.returncode != 0:
        fail(f"'{' '.join(command)}' failed ({process.returncode}):\n{stderr}")
    return usage.ru_utime + usage.ru_stime


def read_pfm(path):
    """The float channels of a colour PFM file, as a flat array (row order is irrelevant here)."""
    with open(path, "rb") as f:
        if f.readline().strip() != b"PF":
            fail(f"{path}: not a colour PFM file")
        width, height = map(int, f.readline().split())
        scale = float(f.readline())
        data = array.array("f")
        data.frombytes(f.read())
    if len(data) != 3 * width * height:
        fail(f"{path}: expected {3 * width * height} floats, found {len(data)}")
    if (scale < 0) != (sys.byteorder == "little"):
        data.byteswap()
    return data


def weighted_mean(values, reference):
    """mean(values / (reference² + ε)) over all entries."""
    return sum(v / (r * r + EPSILON) for v, r in zip(values, reference)) / len(reference)


def study_scene(vcm, scene, args, tmp):
    refs = []
    for seed in (1000, 1001):
        out = os.path.join(tmp, f"ref-{scene}-{seed}.pfm")
        render(vcm, scene, args.resolution, args.reference_iterations, seed, "global", out,
               DEFAULT_RADIUS_FACTOR / 2)
        refs.append(read_pfm(out))
    reference = [0.5 * (x + y) for x, y in zip(*refs)]
    reference_noise = weighted_mean([(x - y) ** 2 / 4 for x, y in zip(*refs)], reference)
    rows = []
    for mode in MODES:
        probe = render(vcm, scene, args.resolution, 2, 7, mode, os.path.join(tmp, "probe.pfm")) / 2
        iterations = max(1, round(args.budget / probe))
        images, cpu = [], []
        for seed in (1, 2):
            out = os.path.join(tmp, f"{scene}-{mode}-{seed}.pfm")
            cpu.append(render(vcm, scene, args.resolution, iterations, seed, mode, out))
            images.append(read_pfm(out))
        errors = [weighted_mean([(x - r) ** 2 for x, r in zip(image, reference)], reference) for image in images]
        relmse = sum(errors) / 2
        variance = weighted_mean([(x - y) ** 2 / 2 for x, y in zip(*images)], reference)
        rows.append({"mode": mode, "iterations": iterations, "cpu": sum(cpu) / 2, "relmse": relmse,
                     "variance": variance, "bias": relmse - variance - reference_noise})
        print(f"scene {scene} {mode}: {rows[-1]}", file=sys.stderr, flush=True)
    return reference_noise, rows


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--vcm", default="target/release/vcm")
    parser.add_argument("--resolution", default="1024x1024")
    parser.add_argument("--scenes", default="0,1,2,3", help="built-in scene ids, comma-separated")
    parser.add_argument("--reference-iterations", type=int, default=24, help="per half of the reference")
    parser.add_argument("--budget", type=float, default=48.0, help="CPU-seconds per test render")
    parser.add_argument("--performance", default="docs/performance.md")
    args = parser.parse_args()
    scenes = [int(s) for s in args.scenes.split(",")]
    if any(s not in SCENES for s in scenes):
        fail(f"--scenes: expected ids among {sorted(SCENES)}")
    if not os.path.exists(args.vcm):
        fail(f"{args.vcm} not found: run `cargo build --release` first")
    results = {}
    with tempfile.TemporaryDirectory() as tmp:
        for scene in scenes:
            results[scene] = study_scene(args.vcm, scene, args, tmp)
    commands = [
        f"{args.vcm} render --scene S -a vcm -r {args.resolution} -i {args.reference_iterations} --seed 1000|1001 "
        f"--radius-mode global --radius-factor {DEFAULT_RADIUS_FACTOR / 2}",
        f"{args.vcm} render --scene S -a vcm -r {args.resolution} -i N --seed 1|2 --radius-mode M",
    ]
    lines = [
        perf_tables.stamp(commands, script="scripts/radius-study.py"),
        f"Equal CPU time: {args.budget:g} CPU-seconds per render (N iterations from a 2-iteration probe); "
        f"relMSE is the mean of seeds 1 and 2 against the reference; variance and bias² as in the script's header. "
        "Reference noise per scene: "
        + ", ".join(f"{scene} {results[scene][0]:.2e}" for scene in scenes) + ".",
        "",
        "| scene | mode | iterations | CPU s | relMSE | variance | bias² | relMSE / global's |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for scene in scenes:
        rows = results[scene][1]
        base = rows[0]["relmse"]
        for row in rows:
            lines.append(
                f"| {scene} {SCENES[scene]} | `{row['mode']}` | {row['iterations']} | {row['cpu']:.1f} | "
                f"{row['relmse']:.3e} | {row['variance']:.3e} | {row['bias']:.2e} | {row['relmse'] / base:.2f} |")
    text = "\n".join(lines)
    print(text)
    perf_tables.replace_between(args.performance, "radius-study", text)


if __name__ == "__main__":
    main()
