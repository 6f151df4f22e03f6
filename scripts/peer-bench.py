#!/usr/bin/env python3
"""Measures this renderer against its peers, Mitsuba 3 and SmallVCM, on this machine in one run.

What it measures (issue #13's table; every figure is a ratio of two runs made minutes apart):

1. Mitsuba's Cornell box (`../shared/scenes/mitsuba/cornell-box/cornell_box.xml`): Mitsuba 3
   `llvm_ad_rgb` `path` renders SPP samples per pixel (median time T over the seeds, JIT compiled
   beforehand); we render the same file for T seconds (`vcm render -t T`) with each of our six
   algorithms. Error: relMSE (`vcm compare`, epsilon 0.01) against `cbox_dict.exr`, the converged
   Mitsuba reference beside the scene (832 spp; its own noise is part of both errors).
2. Mitsuba's `matpreview` (61,600 triangles, environment map, 960x720): per-pixel variance of a
   16-spp image (sample variance over independent seeds, averaged over pixels and channels) times
   the seconds that image took, Mitsuba `path` against our `pt` with 16 iterations.
3. SmallVCM (built from its public source with `g++ -O3 -fopenmp`), its four scenes at 512x512:
   the wall time of the whole process for ITERATIONS iterations of `vcm`, `bpt` and `pt` (three
   alternating rounds of one run of each renderer: the table gives median seconds and the median
   and range of the rounds' ratios, since single runs here spread by ±15 %), and
   `vcm`'s relMSE after EQUAL seconds against a REFERENCE-iteration `vcm` render of ours with
   another seed (cached; its noise is part of both errors). Not SmallVCM's own: it has no seed
   option, so its equal-time render would repeat the first iterations of its reference.
4. A caustic scene (`../shared/scenes/mitsuba/caustic-cbox/cbox.xml`: glass and mirror spheres
   in a Cornell box, 256x256, `max_depth` 6): Mitsuba 3 `path` renders CAUSTIC_SPP samples per
   pixel (median time T over the seeds); we render the file for T seconds with `pt`, `bpt` and
   `vcm`. Error: relMSE against a CAUSTIC_REFERENCE-iteration `vcm` render of ours with another
   seed (cached; no converged Mitsuba image of this scene exists, and one as clean as ours
   would take Mitsuba's path tracer about an hour here: its relMSE, 0.0195 at 64 spp in 3.6 s,
   falls like 1/spp, and the reference's is about 0.0023 x 35 / 4000 = 2e-5). So that this
   reference cannot favour us, the table also gives the channel means of Mitsuba's renders
   against it. Written to its own table (`--only caustic`).

Render times are the renderers' own (Mitsuba: `mi.render` until the image is in memory; ours: the
summary line's render time, which excludes loading), except for SmallVCM's table, which times
whole processes of both. Numbers are meaningful only on a quiet machine.

Setup, done once and cached in target/peer-bench/: a Python virtual environment with
`pip install mitsuba numpy` (the llvm variants need the system's LLVM: `apt-get install libllvm19`,
which this script runs when it is root and the library is missing), and SmallVCM's source (a
checkout given with --smallvcm-src, else `git clone` of github.com/SmallVCM/SmallVCM). A peer
that cannot be set up is reported as SKIPPED with the reason, and the script exits with status 1.

Usage (from the repository root, after `cargo build --release`):

    scripts/peer-bench.py                      # everything, print the tables
    scripts/peer-bench.py --update             # ... and rewrite docs/performance.md's peers table
    scripts/peer-bench.py --quick              # tiny settings: checks the pipeline in ~2 minutes
    scripts/peer-bench.py --only smallvcm      # one part (mitsuba | smallvcm | caustic)
    scripts/peer-bench.py --only caustic --update   # ... and rewrite the caustic table only
"""

import argparse
import importlib.util
import os
import re
import shutil
import statistics
import subprocess
import sys
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
CACHE = os.path.join(ROOT, "target", "peer-bench")
VENV = os.path.join(CACHE, "venv")
SHARED = os.path.join(os.path.dirname(ROOT), "shared", "scenes", "mitsuba")
ALGORITHMS = ["pt", "lt", "ppm", "bpm", "bpt", "vcm"]
SMALLVCM_SCENES = ["cornell-sun", "cornell-area-mirror", "cornell-point", "cornell-env"]
SMALLVCM_URL = "https://github.com/SmallVCM/SmallVCM"
# The seed of the equal-time reference, independent of the default seed (0) of the test renders.
REFERENCE_SEED = 1000


def perf_tables():
    """The stamp and marker helpers of scripts/perf-tables.py (one implementation)."""
    spec = importlib.util.spec_from_file_location("perf_tables", os.path.join(ROOT, "scripts", "perf-tables.py"))
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def log(message):
    print(f"peer-bench: {message}", file=sys.stderr, flush=True)


def fail(message):
    sys.exit(f"peer-bench: {message}")


def run(command, **kwargs):
    result = subprocess.run(command, capture_output=True, text=True, cwd=kwargs.pop("cwd", ROOT), **kwargs)
    if result.returncode != 0:
        fail(f"'{' '.join(command)}' failed ({result.returncode}):\n{result.stdout}\n{result.stderr}")
    return result.stdout + result.stderr


class Skip(Exception):
    """A peer that cannot be set up on this machine: reported, never silently dropped."""


# ---------------------------------------------------------------------------------------------
# Bootstrap: the script re-runs itself with the virtual environment's Python (numpy, mitsuba).


def in_venv():
    return os.path.realpath(sys.prefix) == os.path.realpath(VENV)


def bootstrap():
    python = os.path.join(VENV, "bin", "python")
    if not os.path.exists(python):
        log(f"creating {VENV} (pip install mitsuba numpy; once)")
        os.makedirs(CACHE, exist_ok=True)
        run([sys.executable, "-m", "venv", VENV])
        run([python, "-m", "pip", "install", "--quiet", "mitsuba", "numpy"])
    os.execv(python, [python, os.path.abspath(__file__)] + sys.argv[1:])


LLVM19 = "/usr/lib/x86_64-linux-gnu/libLLVM-19.so"


def llvm_variant():
    """Selects Mitsuba's llvm_ad_rgb variant, installing libllvm19 when root and it is missing.

    Dr.Jit takes the first libLLVM it finds; an older one (Debian 12 also ships 14 and 15) loads
    but aborts while compiling (`Cannot select: fminimum`), so LLVM 19 is installed when it is
    missing and named explicitly (DRJIT_LIBLLVM_PATH) when present."""
    if not os.path.exists(LLVM19) and os.geteuid() == 0 and shutil.which("apt-get") is not None:
        log("Mitsuba's llvm variant needs LLVM 19: apt-get install -y libllvm19")
        run(["apt-get", "install", "-y", "-q", "libllvm19"])
    if os.path.exists(LLVM19):
        os.environ.setdefault("DRJIT_LIBLLVM_PATH", LLVM19)
    import mitsuba as mi

    try:
        mi.set_variant("llvm_ad_rgb")
        return mi
    except Exception as first:  # Mitsuba raises ImportError or RuntimeError without LLVM
        # LLVM 19 was installed above where that is possible (before Dr.Jit was imported):
        # installing again and restarting would repeat this failure forever.
        raise Skip(f"Mitsuba's llvm_ad_rgb variant does not load ({first}); it needs LLVM 19: "
                   "apt-get install libllvm19") from first


# ---------------------------------------------------------------------------------------------
# Our renderer.


def vcm_render(vcm, arguments, output):
    """Runs `vcm render ARGUMENTS -o OUTPUT`; returns (render seconds, process wall seconds)."""
    start = time.perf_counter()
    text = run([vcm, "render"] + arguments + ["-o", output])
    wall = time.perf_counter() - start
    match = re.search(r"(\d+) iterations? in ([0-9.]+) s", text)
    if match is None:
        fail(f"no summary line in the output of vcm render {' '.join(arguments)}:\n{text}")
    return float(match.group(2)), wall


def rel_mse(vcm, image, reference):
    text = run([vcm, "compare", image, reference])
    match = re.search(r"relative MSE:\s+([0-9.eE+-]+)", text)
    if match is None:
        fail(f"no relative MSE in the output of vcm compare:\n{text}")
    return float(match.group(1))


def scratch(*parts):
    path = os.path.join(CACHE, *parts)
    os.makedirs(os.path.dirname(path), exist_ok=True)
    return path


# ---------------------------------------------------------------------------------------------
# Mitsuba 3.


def mitsuba_render(mi, scene, spp, seed, output):
    """Renders with Mitsuba; returns the seconds until the image is in memory."""
    import numpy as np

    start = time.perf_counter()
    image = np.array(mi.render(scene, spp=spp, seed=seed))
    seconds = time.perf_counter() - start
    mi.Bitmap(image).write(output)
    return seconds


def equal_time(vcm, mi, scene, reference, budget, algorithms, names):
    """Mitsuba `path` renders the loaded scene `scene = (scene, path)` with `budget = (spp, seeds)`;
    each of our `algorithms` renders the file for Mitsuba's median time. Returns the table rows
    (renderer, budget, mean seconds, mean relMSE against `reference`) and Mitsuba's images.
    `names` = (scratch folder, name in the log)."""
    (loaded, path), (spp, seeds), (folder, name) = scene, budget, names
    times, errors, outputs = [], [], []
    for seed in range(seeds):
        outputs.append(scratch(folder, f"mitsuba-{seed}.exr"))
        times.append(mitsuba_render(mi, loaded, spp, seed, outputs[-1]))
        errors.append(rel_mse(vcm, outputs[-1], reference))
    seconds = statistics.median(times)
    log(f"{name}: Mitsuba path {spp} spp in {seconds:.2f} s, relMSE {statistics.mean(errors):.3g}")
    rows = [("Mitsuba 3 `path`", f"{spp} spp", seconds, statistics.mean(errors))]
    for algorithm in algorithms:
        ours_times, ours_errors = [], []
        for seed in range(seeds):
            output = scratch(folder, f"{algorithm}-{seed}.exr")
            taken, _ = vcm_render(vcm, ["--scene", path, "-a", algorithm, "-t", f"{seconds:.3f}", "--seed", str(seed),
                                        "--quiet"], output)
            ours_times.append(taken)
            ours_errors.append(rel_mse(vcm, output, reference))
        rows.append((f"ours `{algorithm}`", f"`-t {seconds:.2f}`", statistics.mean(ours_times),
                     statistics.mean(ours_errors)))
        log(f"{name}: ours {algorithm} relMSE {statistics.mean(ours_errors):.3g}")
    return rows, outputs


def mitsuba_cornell(vcm, settings):
    mi = llvm_variant()
    folder = os.path.join(SHARED, "cornell-box")
    path, reference = os.path.join(folder, "cornell_box.xml"), os.path.join(folder, "cbox_dict.exr")
    for needed in (path, reference):
        if not os.path.exists(needed):
            raise Skip(f"{needed} is missing (../shared beside the repository)")
    scene = mi.load_file(path)
    spp, seeds = settings["cornell_spp"], settings["seeds"]
    mitsuba_render(mi, scene, spp, 1000, scratch("cornell", "warmup.exr"))  # JIT compilation
    rows, _ = equal_time(vcm, mi, (scene, path), reference, (spp, seeds), ALGORITHMS, ("cornell", "Cornell box"))
    return rows


def image_stack(mi, paths):
    """The RGB channels of the images at `paths`, stacked: (images, height, width, 3), float64."""
    import numpy as np

    return np.stack([np.array(mi.Bitmap(p), dtype=np.float64)[..., :3] for p in paths])


def variance_across(mi, paths):
    """Mean over pixels and channels of the per-pixel sample variance across images."""
    import numpy as np

    return float(np.mean(np.var(image_stack(mi, paths), axis=0, ddof=1)))


def mitsuba_matpreview(vcm, settings):
    mi = llvm_variant()
    path = os.path.join(SHARED, "matpreview", "matpreview.xml")
    if not os.path.exists(path):
        raise Skip(f"{path} is missing (../shared beside the repository)")
    scene = mi.load_file(path)
    spp, renders = settings["matpreview_spp"], settings["matpreview_renders"]
    mitsuba_render(mi, scene, spp, 1000, scratch("matpreview", "warmup.exr"))
    theirs, theirs_times = [], []
    ours, ours_times = [], []
    for seed in range(renders):
        theirs.append(scratch("matpreview", f"mitsuba-{seed}.exr"))
        theirs_times.append(mitsuba_render(mi, scene, spp, seed, theirs[-1]))
        ours.append(scratch("matpreview", f"pt-{seed}.exr"))
        seconds, _ = vcm_render(vcm, ["--scene", path, "-a", "pt", "-i", str(spp), "--seed", str(seed), "--quiet"],
                                ours[-1])
        ours_times.append(seconds)
    rows = []
    for name, paths, times in (("Mitsuba 3 `path`", theirs, theirs_times), ("ours `pt`", ours, ours_times)):
        rows.append((name, f"{spp} spp", statistics.mean(times), variance_across(mi, paths)))
    log(f"matpreview: {rows}")
    return rows


def channel_means(mi, paths):
    """Per-channel means (R, G, B) of the average of the images at `paths`."""
    import numpy as np

    return [float(m) for m in np.mean(image_stack(mi, paths), axis=(0, 1, 2))]


def mitsuba_caustic(vcm, settings):
    mi = llvm_variant()
    path = os.path.join(SHARED, "caustic-cbox", "cbox.xml")
    if not os.path.exists(path):
        raise Skip(f"{path} is missing (../shared beside the repository)")
    iterations = settings["caustic_reference"]
    reference = scratch("caustic", f"reference-vcm-{iterations}.exr")
    if not os.path.exists(reference):
        log(f"caustic box: reference, {iterations} iterations of our vcm, seed {REFERENCE_SEED} (cached)")
        vcm_render(vcm, ["--scene", path, "-a", "vcm", "-i", str(iterations), "--seed", str(REFERENCE_SEED),
                         "--quiet"], reference)
    scene = mi.load_file(path)
    spp, seeds = settings["caustic_spp"], settings["seeds"]
    mitsuba_render(mi, scene, spp, 1000, scratch("caustic", "warmup.exr"))  # JIT compilation
    rows, outputs = equal_time(vcm, mi, (scene, path), reference, (spp, seeds), ["pt", "bpt", "vcm"],
                               ("caustic", "caustic box"))
    agreement = [m / r for m, r in zip(channel_means(mi, outputs), channel_means(mi, [reference]))]
    side_by_side(mi, [outputs[0], scratch("caustic", "vcm-0.exr")], scratch("caustic", "equal-time.jpg"))
    return rows, agreement


def side_by_side(mi, paths, output):
    """Writes the images at `paths` side by side as an sRGB JPEG (clamped, no exposure change)."""
    import numpy as np

    images = image_stack(mi, paths)
    gap = np.ones((images.shape[1], 4, 3))
    row = np.concatenate([x for image in images for x in (image, gap)][:-1], axis=1)
    bitmap = mi.Bitmap(np.clip(row, 0.0, 1.0)).convert(mi.Bitmap.PixelFormat.RGB, mi.Struct.Type.UInt8, srgb_gamma=True)
    bitmap.write(output, quality=90)


# ---------------------------------------------------------------------------------------------
# SmallVCM.


def smallvcm_binary(source):
    binary = os.path.join(CACHE, "bin", "smallvcm")
    if os.path.exists(binary):
        return binary
    if source is None:
        source = os.path.join(CACHE, "SmallVCM")
        if not os.path.isdir(source):
            log(f"cloning {SMALLVCM_URL} into {source}")
            clone = subprocess.run(["git", "clone", "--quiet", "--depth", "1", SMALLVCM_URL, source],
                                   capture_output=True, text=True)
            if clone.returncode != 0:
                raise Skip(f"SmallVCM's source is not available (git clone failed: {clone.stderr.strip()}); "
                           "give a checkout with --smallvcm-src")
    main = os.path.join(source, "src", "smallvcm.cxx")
    if not os.path.exists(main):
        raise Skip(f"{main} does not exist: --smallvcm-src must be a SmallVCM checkout")
    if shutil.which("g++") is None:
        raise Skip("g++ is not installed (apt-get install g++)")
    log("building SmallVCM with g++ -O3 -fopenmp")
    os.makedirs(os.path.dirname(binary), exist_ok=True)
    run(["g++", "-O3", "-fopenmp", "-std=c++11", "-o", binary, main])
    return binary


def smallvcm_run(binary, arguments, output):
    start = time.perf_counter()
    run([binary] + arguments + ["-o", output], cwd=CACHE)
    return time.perf_counter() - start


def smallvcm(vcm, settings, source):
    binary = smallvcm_binary(source)
    iterations, equal, reference_iterations = settings["iterations"], settings["equal_seconds"], settings["reference"]
    timing, quality = [], []
    for index, name in enumerate(SMALLVCM_SCENES):
        row = [f"{index} {name}"]
        for algorithm in ("vcm", "bpt", "pt"):
            # Alternating rounds: single whole-process runs on a shared machine spread by ±15 %
            # (docs/performance.md), so each round pairs one run of each and the table gives
            # medians and the spread of the rounds' ratios.
            ours_times, theirs_times = [], []
            for _ in range(settings["timing_rounds"]):
                theirs_times.append(smallvcm_run(binary, ["-s", str(index), "-a", algorithm, "-i", str(iterations)],
                                                 scratch("smallvcm", f"{algorithm}-{index}-theirs.hdr")))
                _, ours = vcm_render(vcm, ["--scene", str(index), "-a", algorithm, "-i", str(iterations), "-r",
                                           "512x512", "--quiet"], scratch("smallvcm", f"{algorithm}-{index}-ours.exr"))
                ours_times.append(ours)
            row.append((ours_times, theirs_times))
            log(f"SmallVCM scene {index} {algorithm}: ours {ours_times} s, SmallVCM {theirs_times} s")
        timing.append(row)
        reference = scratch("smallvcm", f"reference-{index}-{reference_iterations}.exr")
        if not os.path.exists(reference):
            log(f"reference of scene {index}: {reference_iterations} iterations of our vcm, seed {REFERENCE_SEED} (cached)")
            vcm_render(vcm, ["--scene", str(index), "-a", "vcm", "-i", str(reference_iterations), "-r", "512x512",
                             "--seed", str(REFERENCE_SEED), "--quiet"], reference + ".part.exr")
            os.replace(reference + ".part.exr", reference)
        theirs_image = scratch("smallvcm", f"equal-{index}-theirs.hdr")
        smallvcm_run(binary, ["-s", str(index), "-a", "vcm", "-t", str(equal)], theirs_image)
        ours_image = scratch("smallvcm", f"equal-{index}-ours.exr")
        vcm_render(vcm, ["--scene", str(index), "-a", "vcm", "-t", str(equal), "-r", "512x512", "--quiet"], ours_image)
        quality.append((f"{index} {name}", rel_mse(vcm, ours_image, reference), rel_mse(vcm, theirs_image, reference)))
    return timing, quality


# ---------------------------------------------------------------------------------------------
# Tables.


def tables(results, settings, commands, stamp):
    out = [stamp(commands, script="scripts/peer-bench.py"), ""]
    if "cornell" in results:
        rows = results["cornell"]
        base = rows[0][3]
        out += ["**Mitsuba's Cornell box, equal time** (relMSE against Mitsuba's 832-spp reference; "
                f"mean of {settings['seeds']} seeds; ratio = ours / Mitsuba 3, below 1 is better):", "",
                "| renderer | budget | seconds | relMSE | ratio |", "|---|---|---|---|---|"]
        out += [f"| {n} | {b} | {s:.2f} | {e:.3g} | {e / base:.2f} |" for n, b, s, e in rows]
        out.append("")
    if "matpreview" in results:
        (_, spp, ts, vs), (_, _, to, vo) = results["matpreview"]
        out += [f"**matpreview, {spp}** (per-pixel variance over {settings['matpreview_renders']} seeds × "
                "seconds per image; ratio = ours / Mitsuba 3):", "",
                "| renderer | seconds | variance | variance × seconds |", "|---|---|---|---|",
                f"| Mitsuba 3 `path` | {ts:.2f} | {vs:.3g} | {vs * ts:.3g} |",
                f"| ours `pt` | {to:.2f} | {vo:.3g} | {vo * to:.3g} (**{vo * to / (vs * ts):.2f}×**) |", ""]
    if "smallvcm" in results:
        timing, quality = results["smallvcm"]
        rounds = settings["timing_rounds"]
        out += [f"**SmallVCM's scenes, 512², {settings['iterations']} iterations, wall time of the whole process** "
                f"(ours / SmallVCM; {rounds} alternating rounds of one run each: median seconds, and the median "
                "of the rounds' ratios with their range; target for vcm ≤ 0.4):", "",
                "| scene | vcm ours / SmallVCM s | ratio | bpt ours / SmallVCM s | ratio | pt ours / SmallVCM s | ratio |",
                "|---|---|---|---|---|---|---|"]

        def cell(ours, theirs):
            ratios = sorted(o / t for o, t in zip(ours, theirs))
            spread = f" ({ratios[0]:.2f}–{ratios[-1]:.2f})" if len(ratios) > 1 else ""
            return (f" {statistics.median(ours):.2f} / {statistics.median(theirs):.2f} | "
                    f"{statistics.median(ratios):.2f}{spread} |")

        for row in timing:
            out.append(f"| {row[0]} |" + "".join(cell(o, t) for o, t in row[1:]))
        out += ["", f"**VCM at equal time ({settings['equal_seconds']} s)**, relMSE against a "
                f"{settings['reference']}-iteration `vcm` render of ours with seed {REFERENCE_SEED} "
                "(target ≤ 0.5):", "",
                "| scene | ours | SmallVCM | ratio |", "|---|---|---|---|"]
        out += [f"| {n} | {o:.3g} | {t:.3g} | {o / t:.2f} |" for n, o, t in quality]
    return "\n".join(out).rstrip()


def caustic_table(results, settings, commands, stamp):
    rows, agreement = results["caustic"]
    base = rows[0][3]
    ratios = ", ".join(f"{r:.4f}" for r in agreement)
    out = [stamp(commands, script="scripts/peer-bench.py"), "",
           f"**Caustic box, equal time** (`caustic-cbox/cbox.xml`, 256², relMSE against a "
           f"{settings['caustic_reference']}-iteration `vcm` render of ours with seed {REFERENCE_SEED}; mean of "
           f"{settings['seeds']} seeds; ratio = ours / Mitsuba 3, below 1 is better; Mitsuba's renders' channel means "
           f"/ the reference's: {ratios}):", "",
           "| renderer | budget | seconds | relMSE | ratio |", "|---|---|---|---|---|"]
    out += [f"| {n} | {b} | {s:.2f} | {e:.3g} | {e / base:.2f} |" for n, b, s, e in rows]
    return "\n".join(out)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true", help="tiny settings, to check the pipeline")
    parser.add_argument("--only", choices=["mitsuba", "smallvcm", "caustic"])
    parser.add_argument("--smallvcm-src", help="a SmallVCM checkout (else it is cloned into target/peer-bench)")
    parser.add_argument("--update", action="store_true", help="rewrite the peers table of docs/performance.md")
    parser.add_argument("--vcm", default=os.path.join(ROOT, "target", "release", "vcm"))
    args = parser.parse_args()
    if not in_venv():
        bootstrap()
    if not os.access(args.vcm, os.X_OK):
        fail(f"'{args.vcm}' is not an executable: run cargo build --release first")
    settings = {"cornell_spp": 256, "seeds": 3, "matpreview_spp": 16, "matpreview_renders": 4,
                "iterations": 8, "timing_rounds": 3, "equal_seconds": 10, "reference": 256, "caustic_spp": 64,
                "caustic_reference": 4000}
    if args.quick:
        settings = {"cornell_spp": 8, "seeds": 1, "matpreview_spp": 2, "matpreview_renders": 2,
                    "iterations": 1, "timing_rounds": 1, "equal_seconds": 1, "reference": 4, "caustic_spp": 4,
                    "caustic_reference": 8}
    flags = " --quick" if args.quick else ""
    commands = [f"scripts/peer-bench.py{flags}" + (f" --only {args.only}" if args.only else "")]
    results, skipped = {}, []
    jobs = [("cornell", "mitsuba", lambda: mitsuba_cornell(args.vcm, settings)),
            ("matpreview", "mitsuba", lambda: mitsuba_matpreview(args.vcm, settings)),
            ("smallvcm", "smallvcm", lambda: smallvcm(args.vcm, settings, args.smallvcm_src)),
            ("caustic", "caustic", lambda: mitsuba_caustic(args.vcm, settings))]
    for name, peer, job in jobs:
        if args.only not in (None, peer):
            continue
        try:
            results[name] = job()
        except Skip as reason:
            skipped.append(f"{name}: SKIPPED: {reason}")
    helpers = perf_tables()
    peers = tables(results, settings, commands, helpers.stamp) if args.only != "caustic" else None
    caustic = caustic_table(results, settings, commands, helpers.stamp) if "caustic" in results else None
    text = "\n\n".join(t for t in (peers, caustic) if t)
    if skipped:
        text += "\n\n" + "\n".join(f"- {s}" for s in skipped)
    print(text)
    with open(scratch("peers.md"), "w") as f:
        f.write(text + "\n")
    if args.update:
        if args.quick or skipped:
            fail("--update needs the full settings and every peer (not --quick, nothing skipped)")
        os.chdir(ROOT)
        # The peers table holds the Mitsuba and SmallVCM parts together: only a run of both
        # rewrites it. The caustic table has a block of its own.
        if args.only is None:
            helpers.replace_between("docs/performance.md", "peers", peers)
        if caustic:
            helpers.replace_between("docs/performance.md", "peers-caustic", caustic)
            shutil.copyfile(scratch("caustic", "equal-time.jpg"), os.path.join("docs", "images", "caustic-equal-time.jpg"))
    sys.exit(1 if skipped else 0)


if __name__ == "__main__":
    main()
