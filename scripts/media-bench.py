#!/usr/bin/env python3
"""Equal-time error of the six algorithms on a scene with participating media (issue #15).

1. Renders a reference of the scene with a long run of one algorithm (default: `vcm`, 4096
   iterations, another seed than the comparison), unless `--reference FILE` is given or the
   cached one exists. The reference must render every path: on cornell-fog, `bpt` (like `pt`)
   misses the fog seen *through* the glass sphere where the sphere's caustic lights it (camera –
   glass – medium vertex – glass – spot light: no connection can join the sub-paths there,
   only merging can), so a `bpt` reference is dark on the sphere and charges vcm with the
   difference (99 % of vcm's relMSE against a 2048-iteration bpt reference came from the
   sphere's 32 × 24 pixel box, where 8 × 8 blocks of a 1024-iteration vcm render are up to
   68 % brighter). A vcm reference keeps a kernel bias that shrinks with its radius; the
   table's vcm row shares part of it.
2. Runs `vcm report --time SECONDS` for pt, lt, ppm, bpm, bpt and vcm against it.
3. Writes the table (iterations, ms per iteration, relative MSE, pt's relMSE over each one's) between
   `<!-- perf-table:media:begin -->` and `<!-- perf-table:media:end -->` in docs/performance.md,
   stamped with the date, commit, machine and commands, and copies the previews of `pt` and
   `vcm` to docs/images/<scene file stem>-{pt,vcm}.png for the README.

Usage (from the repository root, release binary built; only meaningful on a quiet machine):

    scripts/media-bench.py                                 # scenes/cornell-fog.xml, 60 s each
    scripts/media-bench.py --seconds 2 --reference-iterations 8 \\
        --performance /tmp/performance.md --images /tmp   # a quick end-to-end check

Python 3 standard library only.
"""

import argparse
import importlib.util
import json
import os
import shutil
import subprocess
import sys

# The stamp (date, commit, machine) and the marker replacement of scripts/perf-tables.py.
_spec = importlib.util.spec_from_file_location("perf_tables", os.path.join(os.path.dirname(__file__), "perf-tables.py"))
perf_tables = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(perf_tables)

ALGORITHMS = ["pt", "lt", "ppm", "bpm", "bpt", "vcm"]


def fail(message):
    sys.exit(f"media-bench: {message}")


def run(command):
    print("+ " + " ".join(command), file=sys.stderr)
    result = subprocess.run(command, text=True, capture_output=True)
    if result.returncode != 0:
        fail(f"'{' '.join(command)}' failed ({result.returncode}):\n{result.stderr}")
    return result.stdout


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--vcm", default="target/release/vcm")
    parser.add_argument("--scene", default="scenes/cornell-fog.xml")
    parser.add_argument("--resolution", default="128x128")
    parser.add_argument("--seconds", type=float, default=60.0)
    parser.add_argument("--reference", help="an existing reference image (EXR)")
    parser.add_argument("--reference-algorithm", default="vcm")
    parser.add_argument("--reference-iterations", type=int, default=4096)
    parser.add_argument("--work", default="target/media-bench")
    parser.add_argument("--performance", default="docs/performance.md")
    parser.add_argument("--images", default="docs/images")
    parser.add_argument("--algorithms", default=",".join(ALGORITHMS),
                        help="comma-separated; must include pt (the table's ratios are to pt's error)")
    args = parser.parse_args()
    if not os.path.exists(args.vcm):
        fail(f"{args.vcm} not found: build it with `cargo build --release`")
    os.makedirs(args.work, exist_ok=True)

    reference = args.reference
    label = os.path.splitext(os.path.basename(args.scene))[0]
    reference_command = None
    if reference is None:
        reference = os.path.join(
            args.work, f"{label}-{args.reference_algorithm}-{args.reference_iterations}-{args.resolution}.exr")
        reference_command = [args.vcm, "render", "--scene", args.scene, "-a", args.reference_algorithm,
                             "-i", str(args.reference_iterations), "-r", args.resolution, "--seed", "1000",
                             "--quiet", "-o", reference]
        if not os.path.exists(reference):
            run(reference_command)
    report_dir = os.path.join(args.work, "report")
    algorithms = args.algorithms.split(",")
    if "pt" not in algorithms:
        fail("--algorithms must include pt")
    report_command = [args.vcm, "report", "--scenes", args.scene, "--algorithms", ",".join(algorithms),
                      "--time", f"{args.seconds:g}", "-r", args.resolution, "--reference",
                      f"{args.scene}={reference}", "-o", report_dir]
    run(report_command)
    with open(os.path.join(report_dir, "report.json")) as f:
        report = json.load(f)
    (scene,) = report["scenes"]
    results = {r["algorithm"]: r for r in scene["results"]}
    missing = [a for a in algorithms if a not in results or results[a]["relative_mse"] is None]
    if missing:
        fail(f"no error measured for {', '.join(missing)}")
    pt_error = results["pt"]["relative_mse"]

    commands = ([" ".join(reference_command)] if reference_command else []) + [" ".join(report_command)]
    lines = [perf_tables.stamp(commands, script="scripts/media-bench.py"), "",
             "| algorithm | iterations | ms / iteration | relMSE | pt's relMSE / this |", "|---|---|---|---|---|"]
    for a in algorithms:
        r = results[a]
        lines.append(f"| {a} | {r['iterations']} | {r['ms_per_iteration']:.0f} | {r['relative_mse']:.3e} | "
                     f"{pt_error / r['relative_mse']:.2f} |")
    text = "\n".join(lines)
    print(text)
    perf_tables.replace_between(args.performance, "media", text)
    os.makedirs(args.images, exist_ok=True)
    for a in [a for a in ("pt", "vcm") if a in results]:
        shutil.copyfile(os.path.join(report_dir, results[a]["preview"]),
                        os.path.join(args.images, f"{label}-{a}.png"))


if __name__ == "__main__":
    main()
