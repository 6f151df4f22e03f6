#!/usr/bin/env python3
"""Equal-time error of the six algorithms on a scene with participating media (issue #15).

1. Renders a reference of the scene with a long run of one algorithm (default: `bpt`, another
   seed than the comparison), unless `--reference FILE` is given or the cached one exists.
2. Runs `vcm report --time SECONDS` for pt, lt, ppm, bpm, bpt and vcm against it.
3. Writes the table (iterations, ms per iteration, relative MSE, relMSE / vcm's) between
   `<!-- perf-table:media:begin -->` and `<!-- perf-table:media:end -->` in docs/performance.md,
   stamped with the date, commit, machine and commands, and copies the previews of `pt` and
   `vcm` to docs/images/<scene>-{pt,vcm}.png for the README.

Usage (from the repository root, release binary built; only meaningful on a quiet machine):

    scripts/media-bench.py                                 # cornell-fog, 60 s each
    scripts/media-bench.py --seconds 2 --reference-iterations 8 \\
        --performance /tmp/performance.md --images /tmp   # a quick end-to-end check

Python 3 standard library only.
"""

import argparse
import datetime
import json
import os
import shutil
import subprocess
import sys

ALGORITHMS = ["pt", "lt", "ppm", "bpm", "bpt", "vcm"]


def fail(message):
    sys.exit(f"media-bench: {message}")


def run(command):
    print("+ " + " ".join(command), file=sys.stderr)
    result = subprocess.run(command, text=True, capture_output=True)
    if result.returncode != 0:
        fail(f"'{' '.join(command)}' failed ({result.returncode}):\n{result.stderr}")
    return result.stdout


def machine():
    model = "unknown CPU"
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if line.startswith("model name"):
                    model = line.split(":", 1)[1].strip()
                    break
    except OSError:
        pass
    return f"{model}, {os.cpu_count()} logical cores"


def commit():
    try:
        return subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True, text=True,
                              check=True).stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        return "unknown"


def replace_between(path, name, text):
    begin, end = f"<!-- perf-table:{name}:begin -->", f"<!-- perf-table:{name}:end -->"
    with open(path) as f:
        content = f.read()
    if begin not in content or end not in content:
        fail(f"{path} has no {begin} ... {end} markers")
    head, rest = content.split(begin, 1)
    _, tail = rest.split(end, 1)
    with open(path, "w") as f:
        f.write(head + begin + "\n" + text + end + tail)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--vcm", default="target/release/vcm")
    parser.add_argument("--scene", default="cornell-fog")
    parser.add_argument("--resolution", default="256x256")
    parser.add_argument("--seconds", type=float, default=60.0)
    parser.add_argument("--reference", help="an existing reference image (EXR)")
    parser.add_argument("--reference-algorithm", default="bpt")
    parser.add_argument("--reference-iterations", type=int, default=2048)
    parser.add_argument("--work", default="target/media-bench")
    parser.add_argument("--performance", default="docs/performance.md")
    parser.add_argument("--images", default="docs/images")
    args = parser.parse_args()
    if not os.path.exists(args.vcm):
        fail(f"{args.vcm} not found: build it with `cargo build --release`")
    os.makedirs(args.work, exist_ok=True)

    reference = args.reference
    reference_command = None
    if reference is None:
        reference = os.path.join(
            args.work, f"{args.scene}-{args.reference_algorithm}-{args.reference_iterations}-{args.resolution}.exr")
        reference_command = [args.vcm, "render", "--scene", args.scene, "-a", args.reference_algorithm,
                             "-i", str(args.reference_iterations), "-r", args.resolution, "--seed", "1000",
                             "--quiet", "-o", reference]
        if not os.path.exists(reference):
            run(reference_command)
    report_dir = os.path.join(args.work, "report")
    report_command = [args.vcm, "report", "--scenes", args.scene, "--algorithms", ",".join(ALGORITHMS),
                      "--time", f"{args.seconds:g}", "-r", args.resolution, "--reference",
                      f"{args.scene}={reference}", "-o", report_dir]
    run(report_command)
    with open(os.path.join(report_dir, "report.json")) as f:
        report = json.load(f)
    (scene,) = report["scenes"]
    results = {r["algorithm"]: r for r in scene["results"]}
    missing = [a for a in ALGORITHMS if a not in results or results[a]["relative_mse"] is None]
    if missing:
        fail(f"no error measured for {', '.join(missing)}")
    vcm_error = results["vcm"]["relative_mse"]

    date = datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M UTC")
    lines = [
        f"Measured {date}, commit {commit()}, {machine()}, by `scripts/media-bench.py`:",
        "",
    ]
    if reference_command:
        lines += [f"    {' '.join(reference_command)}"]
    lines += [f"    {' '.join(report_command)}", "", "| algorithm | iterations | ms / iteration | relMSE | relMSE / vcm's |",
              "|---|---|---|---|---|"]
    for a in ALGORITHMS:
        r = results[a]
        lines.append(f"| {a} | {r['iterations']} | {r['ms_per_iteration']:.0f} | {r['relative_mse']:.3e} | "
                     f"{r['relative_mse'] / vcm_error:.2f} |")
    text = "\n".join(lines) + "\n"
    print(text)
    replace_between(args.performance, "media", text)
    os.makedirs(args.images, exist_ok=True)
    for a in ("pt", "vcm"):
        shutil.copyfile(os.path.join(report_dir, results[a]["preview"]),
                        os.path.join(args.images, f"{args.scene}-{a}.png"))


if __name__ == "__main__":
    main()
