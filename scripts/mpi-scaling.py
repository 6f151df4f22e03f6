#!/usr/bin/env python3
"""Measures issue #16's scaling table and rewrites it in docs/distributed.md.

For pt, bpt and vcm on a built-in Cornell scene: the wall-clock time of one process with 2
threads (`vcm render --threads 2`) against 2 MPI ranks with 1 thread each (`mpirun -np 2 vcm
render --threads 1`), same seed and iterations (the images are identical, scripts/mpi-identity.sh
checks that), each the best of --repeats runs. From the measured time per iteration it derives
the data volume rank 0 receives per round (12 bytes per pixel from every other rank,
docs/distributed.md) and the projected efficiency at 64 ranks for a given link bandwidth:
T / (T + 12·P·63 / B), T the time of one iteration on one 2-thread node: the model of
docs/distributed.md, which counts transfer into rank 0 and neither rank 0's additions nor
latency. The table between `<!-- mpi-scaling:begin -->` and `<!-- mpi-scaling:end -->` is
replaced, stamped with date, commit, machine and commands. Python 3 standard library only;
numbers are only meaningful on a quiet machine.

Usage: scripts/mpi-scaling.py SINGLE_BIN MPI_BIN [--resolution 512x512] [--iterations 32]
       [--repeats 3] [--bandwidth-gbit 10] [--doc docs/distributed.md]
"""

import argparse
import os
import re
import subprocess
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from importlib import import_module  # noqa: E402

perf = import_module("perf-tables")

ALGORITHMS = ["pt", "bpt", "vcm"]
MPI_ENV = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1")


def timed(command, env=None):
    start = time.perf_counter()
    result = subprocess.run(command, capture_output=True, text=True, env=env)
    wall = time.perf_counter() - start
    if result.returncode != 0:
        sys.exit(f"mpi-scaling: '{' '.join(command)}' failed:\n{result.stderr}")
    return wall


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("single")
    parser.add_argument("mpi")
    parser.add_argument("--resolution", default="512x512")
    parser.add_argument("--iterations", type=int, default=32)
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--bandwidth-gbit", type=float, default=10.0)
    parser.add_argument("--scene", default="1")
    parser.add_argument("--doc", default="docs/distributed.md")
    args = parser.parse_args()
    width, height = (int(v) for v in args.resolution.split("x"))
    pixels = width * height
    common = ["render", "--scene", args.scene, "--resolution", args.resolution, "--iterations",
              str(args.iterations), "--quiet", "-o", "/tmp/vcm-mpi-scaling.exr"]
    rows = []
    for algorithm in ALGORITHMS:
        threads = [args.single] + common + ["--algorithm", algorithm, "--threads", "2"]
        ranks = ["mpirun", "--oversubscribe", "-np", "2", args.mpi] + common + ["--algorithm", algorithm,
                                                                                "--threads", "1"]
        t_threads = min(timed(threads) for _ in range(args.repeats))
        t_ranks = min(timed(ranks, MPI_ENV) for _ in range(args.repeats))
        per_iteration = t_threads / args.iterations
        round_bytes = 12 * pixels * 63
        transfer = round_bytes * 8 / (args.bandwidth_gbit * 1e9)
        efficiency = per_iteration / (per_iteration + transfer)
        rows.append((algorithm, t_threads, t_ranks, per_iteration, efficiency))
        print(f"{algorithm}: 1x2 threads {t_threads:.2f} s, 2x1 ranks {t_ranks:.2f} s", file=sys.stderr)
    commands = [" ".join(["SINGLE"] + common + ["--algorithm", "A", "--threads", "2"]),
                " ".join(["mpirun -np 2 MPI"] + common[0:] + ["--algorithm", "A", "--threads", "1"])]
    out = [
        perf.stamp(commands, script="scripts/mpi-scaling.py"),
        f"Wall-clock seconds of the whole process, best of {args.repeats}; scene {args.scene}, "
        f"{args.resolution}, {args.iterations} iterations. Rank 0 receives 12 B per pixel per remote "
        f"iteration: {12 * pixels / 1e6:.2f} MB at this size, {12 * pixels * 63 / 1e6:.0f} MB per round "
        f"at 64 ranks. Projected efficiency at 64 ranks with a {args.bandwidth_gbit:g} Gbit/s link into "
        "rank 0: T / (T + 12·P·63·8 / B), T = time per iteration of one 2-thread process (transfer only).",
        "",
        "| algorithm | 1 process x 2 threads (s) | 2 ranks x 1 thread (s) | ranks / threads | "
        "time per iteration T (ms) | projected efficiency at 64 ranks |",
        "|---|---|---|---|---|---|",
    ]
    for algorithm, t_threads, t_ranks, per_iteration, efficiency in rows:
        out.append(f"| {algorithm} | {t_threads:.2f} | {t_ranks:.2f} | {t_ranks / t_threads:.2f} | "
                   f"{1e3 * per_iteration:.1f} | {100 * efficiency:.0f} % |")
    table = "\n".join(out)
    with open(args.doc) as f:
        text = f.read()
    pattern = re.compile(r"(<!-- mpi-scaling:begin -->\n).*?(\n<!-- mpi-scaling:end -->)", re.S)
    if not pattern.search(text):
        sys.exit(f"mpi-scaling: no mpi-scaling markers in {args.doc}")
    text = pattern.sub(lambda m: m.group(1) + table + m.group(2), text)
    with open(args.doc, "w") as f:
        f.write(text)
    print(table)


if __name__ == "__main__":
    main()
