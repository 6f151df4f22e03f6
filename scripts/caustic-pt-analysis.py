#!/usr/bin/env python3
"""Time per sample and roulette efficiency of our `pt` on a Mitsuba scene (by default the
shared caustic box), the two measurements of docs/performance.md, "The caustic box's path
tracer", that `scripts/equal-spp-variance.py` (noise per sample) does not make.

1. Time per sample: ROUNDS alternating rounds, each one Mitsuba 3 `path` render of SPP samples
   per pixel at the given resolution (`mi.render` until the image is in memory, after one
   warm-up render that compiles its kernels, as scripts/peer-bench.py times it) and our
   `vcm render -a pt -i SPP` with our default roulette and with `--rr-depth 5` (Mitsuba's rule),
   two threads each, our time from the summary line (the render without loading). Prints the
   medians and the ratios ours / Mitsuba.
2. Which roulette is more efficient for us: SEEDS renders with each rule (interleaved), the
   per-pixel relative variance across the seeds (mean over pixels and channels of
   var / (mean² + 0.01), the weighting of `vcm compare`'s relMSE) times the median render
   seconds, and their ratio.

Run it with a Python that has `mitsuba` and `numpy` (scripts/peer-bench.py creates one in
target/peer-bench/venv; the llvm variants need `apt-get install libllvm19`), from the
repository root after `cargo build --release`, with both cores free:

    target/peer-bench/venv/bin/python scripts/caustic-pt-analysis.py
"""

import argparse
import importlib.util
import os
import re
import statistics
import subprocess
import sys
import tempfile
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
DEFAULT_SCENE = os.path.join(ROOT, "..", "shared", "scenes", "mitsuba", "caustic-cbox", "cbox.xml")


def equal_spp_variance():
    """scripts/equal-spp-variance.py as a module (a file name with a hyphen: loaded by path), for
    its `read_pfm` and `import_mitsuba`."""
    spec = importlib.util.spec_from_file_location("equal_spp_variance",
                                                  os.path.join(ROOT, "scripts", "equal-spp-variance.py"))
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def ours(vcm, scene, size, spp, seed, extra, output):
    """Renders with `vcm render -a pt`; returns the render seconds of its summary line."""
    command = [vcm, "render", "--scene", scene, "-a", "pt", "-i", str(spp), "-r", size,
               "--seed", str(seed), "-o", output] + extra
    text = subprocess.run(command, check=True, capture_output=True, text=True).stderr
    match = re.search(r"(\d+) iterations? in ([0-9.]+) s", text)
    if match is None:
        sys.exit(f"no summary line in the output of {' '.join(command)}:\n{text}")
    return float(match.group(2))


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("scene", nargs="?", default=DEFAULT_SCENE, help="a Mitsuba 3 XML file [the caustic box]")
    parser.add_argument("--resolution", type=int, default=256, help="square film size [256]")
    parser.add_argument("--spp", type=int, default=64, help="samples per pixel of each render [64]")
    parser.add_argument("--rounds", type=int, default=3, help="alternating timing rounds [3]")
    parser.add_argument("--seeds", type=int, default=8, help="renders per roulette rule [8]")
    parser.add_argument("--variant", default="llvm_ad_rgb", help="Mitsuba variant [llvm_ad_rgb]")
    parser.add_argument("--vcm", default=os.path.join(ROOT, "target", "release", "vcm"))
    args = parser.parse_args()
    helpers = equal_spp_variance()
    mi, np = helpers.import_mitsuba(args.vcm, args.variant)
    if not os.path.exists(args.scene):
        sys.exit(f"{args.scene} not found")
    read_pfm = helpers.read_pfm
    n, spp = args.resolution, args.spp
    size = f"{n}x{n}"
    rules = [("albedo (default)", []), ("--rr-depth 5", ["--rr-depth", "5"])]

    scene = mi.load_file(args.scene)
    film = mi.traverse(scene.sensors()[0].film())
    film["size"] = [n, n]
    film.update()
    np.array(mi.render(scene, spp=spp, seed=0))  # warm-up: compiles the kernels
    mitsuba_seconds, our_seconds = [], {name: [] for name, _ in rules}
    with tempfile.TemporaryDirectory() as tmp:
        for round_ in range(1, args.rounds + 1):
            start = time.perf_counter()
            np.array(mi.render(scene, spp=spp, seed=round_))
            mitsuba_seconds.append(time.perf_counter() - start)
            for name, extra in rules:
                our_seconds[name].append(ours(args.vcm, args.scene, size, spp, round_, extra,
                                              os.path.join(tmp, "t.pfm")))
            print(f"round {round_}: Mitsuba {mitsuba_seconds[-1]:.2f} s, ours "
                  + ", ".join(f"{name} {our_seconds[name][-1]:.2f} s" for name, _ in rules), flush=True)

        images = {name: [] for name, _ in rules}
        seconds = {name: [] for name, _ in rules}
        for seed in range(1, args.seeds + 1):
            for name, extra in rules:
                out = os.path.join(tmp, f"s{seed}.pfm")
                seconds[name].append(ours(args.vcm, args.scene, size, spp, seed, extra, out))
                images[name].append(read_pfm(out, np))

    print(f"\n{args.scene}: {size}, {spp} spp; {args.rounds} alternating rounds, two threads")
    print("| renderer | median seconds | ours / Mitsuba |")
    print("|---|---:|---:|")
    m = statistics.median(mitsuba_seconds)
    print(f"| Mitsuba 3 `{args.variant}` `path` | {m:.2f} | |")
    for name, _ in rules:
        s = statistics.median(our_seconds[name])
        print(f"| ours `pt`, roulette {name} | {s:.2f} | {s / m:.2f} |" if m > 0 else f"| ours `pt`, roulette {name} | {s:.2f} | – |")

    print(f"\nRoulette efficiency, {args.seeds} seeds per rule: per-pixel relative variance × median seconds")
    print("| roulette | relative variance | median seconds | product | / default |")
    print("|---|---:|---:|---:|---:|")
    products = {}
    for name, _ in rules:
        stack = np.array(images[name])
        mean, var = stack.mean(axis=0), stack.var(axis=0, ddof=1)
        relative = float((var / (mean ** 2 + 0.01)).mean())
        s = statistics.median(seconds[name])
        products[name] = relative * s
        base = products[rules[0][0]]
        # The summary line gives seconds to 0.01 s: a tiny render may read 0.
        ratio = f"{products[name] / base:.2f}" if base > 0 else "–"
        print(f"| {name} | {relative:.4f} | {s:.2f} | {products[name]:.4f} | {ratio} |")


if __name__ == "__main__":
    main()
