#!/usr/bin/env python3
"""Where a VCM iteration's instructions go, ours against SmallVCM's, on SmallVCM's four scenes.

Runs one 512x512 VCM iteration of each renderer on one thread under valgrind's callgrind
(instruction counts do not depend on the machine's load) and splits the instructions into the
categories both programs have: ray casting (closest hit and shadow rays, whoever calls them),
merging (the range queries with everything they call), next-event estimation, vertex
connections, light vertices connected to the camera (each without its shadow rays), the rest of
the iteration, and what lies outside the iteration (setup, writing the image).

With --time it also samples where the time goes (`perf record -e cpu-clock`, one thread, four
iterations of ours and two of SmallVCM's) and groups the samples by the function they land in:
merging (our `hash_grid` and `merge` functions; SmallVCM's `HashGrid::Process`), ray casting
(our BVH and `Scene::intersect`/`occluded`; SmallVCM's `Intersect`/`Occluded` functions) and the
rest. Self time only: what a merge or a shadow ray calls outside those functions (a BSDF
evaluation) counts as the rest.

Usage: scripts/instruction-split.py --vcm target/release/vcm --smallvcm PATH/TO/smallvcm
       [--scenes 0 1 2 3] [--out DIR] [--time]
SmallVCM is built from its public source in a scratch folder (g++ -O3 -fopenmp, see
scripts/peer-bench.py); nothing of it is kept here. Prints a Markdown table (docs/performance.md,
"Instructions per VCM iteration against SmallVCM").
"""

import argparse
import os
import re
import subprocess
import sys
import tempfile

# Callee symbols (as callgrind_annotate names them, without the file) of each category.
OURS = {
    "ray casting": ["scene::scene::Scene::intersect", "scene::scene::Scene::occluded"],
    "merging": ["render::vcm::merge::merge", "render::hash_grid::HashGrid::plan"],
    "next event": ["render::vcm::connect::next_event"],
    "connections": ["render::vcm::connect::connect_vertices"],
    "to the camera": ["render::vcm::connect::connect_to_camera"],
    # Whichever the compiler kept as a function (the outer one calls the inner, if both are).
    "iteration": ["render::vcm::VcmEngine::run_iteration", "render::vcm::Engine<S>::run_iteration"],
}
THEIRS = {
    "ray casting": ["GeometryList::Intersect(Ray const&, Isect&) const", "Scene::Occluded(Vec3x<float> const&, Vec3x<float> const&, float) const"],
    "merging": ["void HashGrid::Process<VertexCM::PathVertex<true>, VertexCM::RangeQuery>"],
    "next event": ["VertexCM::DirectIllumination"],
    "connections": [],  # inlined into RunIteration
    "to the camera": ["VertexCM::ConnectToCamera"],
    "iteration": ["VertexCM::RunIteration(int)"],
}
# Shadow-ray functions, subtracted from their callers' categories.
SHADOW = {"ours": "scene::scene::Scene::occluded", "theirs": "Scene::Occluded("}
# The closest-hit entry of SmallVCM counted only when called by the iteration itself (it also
# calls itself through the shadow rays' code path).
THEIR_INTERSECT_CALLER = "VertexCM::RunIteration"

LINE = re.compile(r"^\s*([\d,]+)\s+\([^)]*\)\s+([<*>])\s+(.*)$")


def callgrind(command, out, reuse=False):
    if not reuse:
        # One OpenMP thread for SmallVCM (our side takes `--threads 1`).
        env = dict(os.environ, OMP_NUM_THREADS="1")
        subprocess.run(["valgrind", "--tool=callgrind", f"--callgrind-out-file={out}"] + command,
                       check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, env=env)
    # Run from the output folder: from inside the repository, callgrind_annotate shortens the
    # source paths and then loses the call edges of functions that had two file names.
    return subprocess.run(["callgrind_annotate", "--tree=caller", "--threshold=100", os.path.abspath(out)], check=True,
                          capture_output=True, text=True, cwd=os.path.dirname(os.path.abspath(out))).stdout


def symbol(text):
    """The function part of `file:function [object]` (or `file:function (Nx) [object]`)."""
    text = re.sub(r"\s+\(\d[\d,]*x\)", "", text)
    text = re.sub(r"\s+\[[^\]]*\]$", "", text)
    return text.split(":", 1)[1] if ":" in text and not text.startswith("???:") else text.replace("???:", "")


def edges(report):
    """Per callee block: (callee, [(caller, inclusive cost of the calls)]), and the total."""
    total = int(re.search(r"([\d,]+)\s+\(100\.0%\)\s+PROGRAM TOTALS", report).group(1).replace(",", ""))
    blocks, callers = [], []
    for line in report.splitlines():
        m = LINE.match(line)
        if not m:
            if not line.strip():
                callers = []
            continue
        cost, kind, name = int(m.group(1).replace(",", "")), m.group(2), m.group(3)
        if kind == "<":
            callers.append((symbol(name), cost))
        elif kind == "*":
            blocks.append((symbol(name), name, callers))
            callers = []
    return blocks, total


def inclusive(blocks, name, caller=None, exact=True):
    """Summed cost of the calls into function `name`, optionally only from callers whose name
    starts with `caller`. Rust symbols match exactly (a prefix would take in their closures),
    C++ ones (`exact=False`) up to their parameter lists. Only the real symbols count (the lines
    that name the object file), not the per-file shares of inlined code."""
    cost = 0
    for callee, raw, callers in blocks:
        if not (callee == name if exact else callee.startswith(name)) or "[" not in raw:
            continue
        cost += sum(c for who, c in callers if caller is None or who.startswith(caller))
    return cost


TIME_GROUPS = {
    "ours": [("merging", re.compile(r"hash_grid|merge::")),
             ("ray casting", re.compile(r"Bvh::|Scene::intersect|Scene::occluded|triangle"))],
    "theirs": [("merging", re.compile(r"HashGrid::Process")),
               ("ray casting", re.compile(r"Intersect|Occluded"))],
}


def time_split(command, data, groups):
    """Shares (percent) of the cpu-clock samples of `command` by group of function names."""
    env = dict(os.environ, OMP_NUM_THREADS="1")
    subprocess.run(["perf", "record", "-q", "-e", "cpu-clock", "-o", data] + command, check=True,
                   stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, env=env)
    report = subprocess.run(["perf", "report", "-i", data, "--no-children", "--stdio", "--sort", "symbol"],
                            check=True, capture_output=True, text=True).stdout
    shares = {name: 0.0 for name, _ in groups}
    shares["rest"] = 0.0
    for line in report.splitlines():
        m = re.match(r"^\s+([\d.]+)%\s+\[[^\]]*\]\s+(.*)$", line)
        if not m:
            continue
        share, function = float(m.group(1)), m.group(2)
        group = next((name for name, pattern in groups if pattern.search(function)), "rest")
        shares[group] += share
    return shares


def split(blocks, total, table, shadow, ours):
    out = {}
    for category, names in table.items():
        if category == "iteration":
            out[category] = max(inclusive(blocks, name, exact=ours) for name in names)
            continue
        cost = 0
        for name in names:
            if not ours and category == "ray casting" and name.startswith("GeometryList::Intersect"):
                cost += inclusive(blocks, name, THEIR_INTERSECT_CALLER, exact=False)
            else:
                cost += inclusive(blocks, name, exact=ours)
            if category in ("next event", "connections", "to the camera"):
                caller = name.split("(")[0]
                cost -= inclusive(blocks, shadow, caller, exact=ours)
        out[category] = cost
    out["total"] = total
    return out


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--vcm", required=True)
    parser.add_argument("--smallvcm", required=True)
    parser.add_argument("--scenes", nargs="*", type=int, default=[0, 1, 2, 3])
    parser.add_argument("--out", default=None, help="keep the callgrind files here")
    parser.add_argument("--time", action="store_true", help="also sample the time split with perf")
    parser.add_argument("--reuse", action="store_true",
                        help="annotate the callgrind files already in --out instead of running")
    args = parser.parse_args()
    out = args.out or tempfile.mkdtemp(prefix="instruction-split-")
    os.makedirs(out, exist_ok=True)
    rows, times = [], []
    for scene in args.scenes:
        print(f"scene {scene}: ours", file=sys.stderr)
        ours_report = callgrind([args.vcm, "render", "--scene", str(scene), "-a", "vcm", "-i", "1", "-r", "512x512",
                                 "--threads", "1", "--seed", "3", "--quiet", "-o", f"{out}/ours{scene}.exr"],
                                f"{out}/ours{scene}.cg", args.reuse)
        print(f"scene {scene}: SmallVCM", file=sys.stderr)
        theirs_command = [args.smallvcm, "-s", str(scene), "-a", "vcm", "-i", "1", "-o", f"{out}/smallvcm{scene}.bmp"]
        theirs_report = callgrind(theirs_command, f"{out}/smallvcm{scene}.cg", args.reuse)
        ours = split(*edges(ours_report), OURS, SHADOW["ours"], True)
        theirs = split(*edges(theirs_report), THEIRS, SHADOW["theirs"], False)
        rows.append((scene, ours, theirs))
        if args.time:
            print(f"scene {scene}: perf", file=sys.stderr)
            ours_time = time_split([args.vcm, "render", "--scene", str(scene), "-a", "vcm", "-i", "4", "-r", "512x512",
                                    "--threads", "1", "--quiet", "-o", f"{out}/ours{scene}-perf.exr"],
                                   f"{out}/ours{scene}.perf", TIME_GROUPS["ours"])
            theirs_time = time_split([args.smallvcm, "-s", str(scene), "-a", "vcm", "-i", "2",
                                      "-o", f"{out}/smallvcm{scene}-perf.bmp"],
                                     f"{out}/smallvcm{scene}.perf", TIME_GROUPS["theirs"])
            times.append((scene, ours_time, theirs_time))

    def m(x):
        return f"{x / 1e6:,.0f}"

    # SmallVCM's connections are inlined into its iteration loop, so they are compared together
    # with the rest of the iteration (ours given separately in parentheses).
    columns = ["ray casting", "merging", "next event", "to the camera", "connections and the rest"]
    print("| scene | renderer | total | outside the iteration | " + " | ".join(columns) + " | iteration without ray casting |")
    print("|---|---|" + "---:|" * (len(columns) + 3))
    for scene, ours, theirs in rows:
        values = {}
        for name, r in (("ours", ours), ("SmallVCM", theirs)):
            named = r["ray casting"] + r["merging"] + r["next event"] + r["to the camera"]
            v = {c: r[c] for c in columns[:4]}
            v["connections and the rest"] = r["iteration"] - named
            v["total"], v["outside"] = r["total"], r["total"] - r["iteration"]
            v["without rays"] = r["iteration"] - r["ray casting"]
            values[name] = v
        for name in ("ours", "SmallVCM"):
            v = values[name]
            cells = [m(v[c]) for c in columns]
            if name == "ours":
                cells[-1] += f" ({m(ours['connections'])})"
            print(f"| {scene} | {name} | {m(v['total'])} | {m(v['outside'])} | " + " | ".join(cells)
                  + f" | {m(v['without rays'])} |")
        o, t = values["ours"], values["SmallVCM"]
        ratio = [f"{o[c] / t[c]:.2f}" if t[c] else "" for c in ["total", "outside"] + columns + ["without rays"]]
        print(f"| {scene} | ours / SmallVCM | " + " | ".join(ratio) + " |")
    if times:
        print("\n| scene | renderer | merging | ray casting | rest |")
        print("|---|---|---:|---:|---:|")
        for scene, ours_time, theirs_time in times:
            for name, t in (("ours", ours_time), ("SmallVCM", theirs_time)):
                print(f"| {scene} | {name} | {t['merging']:.1f} % | {t['ray casting']:.1f} % | {t['rest']:.1f} % |")
    print(f"\n(millions of instructions; callgrind files in {out})", file=sys.stderr)


if __name__ == "__main__":
    main()
