#!/usr/bin/env python3
"""Per-pixel variance at equal samples per pixel: our `pt` against Mitsuba 3's `path`.

Renders a Mitsuba scene file SEEDS times with each renderer at the same resolution and samples
per pixel (Mitsuba: `mi.render(scene, seed=s)` with the file's sampler; ours: `vcm render -a pt
-i SPP --seed s`, the file's film mode), and prints the relative variance
Σ_pixels,channels var / Σ mean² of each (the variance across the seeds, unbiased), its ratio
ours / Mitsuba, and the same split into the pixels that see an emitter (mean above
--emitter-threshold, dilated by 4 pixels) and the rest. Counts only, no timing: what it measures
is the estimators' noise per sample, independent of speed (docs/film.md).

Give --resolution the aspect ratio of the file's film: at another shape the two renderers frame
the scene differently (on matpreview, 683x512, a 128x128 film gave channel means 0.93-1.04x
Mitsuba's; 171x128 gives 0.999-1.000x).

Run it with a Python that has `mitsuba` and `numpy` (scripts/peer-bench.py creates one in
target/peer-bench/venv; the llvm variants need `apt-get install libllvm19`), from the repository
root after `cargo build --release`:

    target/peer-bench/venv/bin/python scripts/equal-spp-variance.py \\
        ../shared/scenes/mitsuba/cornell-box/cornell_box.xml --resolution 128 --spp 64 --seeds 6
"""

import argparse
import os
import re
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def read_pfm(path, np):
    """A PFM image as a float array (height, width, 3), top row first."""
    with open(path, "rb") as f:
        kind = f.readline().strip()
        width, height = map(int, f.readline().split())
        scale = float(f.readline())
        data = np.frombuffer(f.read(), dtype="<f4" if scale < 0 else ">f4")
    channels = 3 if kind == b"PF" else 1
    image = data.reshape(height, width, channels)[::-1].astype(np.float64)
    return image if channels == 3 else np.repeat(image, 3, axis=2)


def relative_variance(images, mask, np):
    """Σ var / Σ mean² over the pixels in `mask` (all channels), from images (seeds, h, w, 3)."""
    mean = images.mean(axis=0)
    var = images.var(axis=0, ddof=1)
    return var[mask].sum() / max((mean[mask] ** 2).sum(), 1e-300), var[mask].sum()


def dilate(mask, steps, np):
    out = mask.copy()
    for _ in range(steps):
        grown = out.copy()
        grown[1:, :] |= out[:-1, :]
        grown[:-1, :] |= out[1:, :]
        grown[:, 1:] |= out[:, :-1]
        grown[:, :-1] |= out[:, 1:]
        out = grown
    return out


def import_mitsuba(vcm, variant):
    """The modules `mitsuba` (set to `variant`) and `numpy`; exits with what to do when either is
    missing or when our binary `vcm` is not built."""
    try:
        import mitsuba as mi
        import numpy as np
    except ImportError as e:
        sys.exit(f"needs mitsuba and numpy ({e}); run it with target/peer-bench/venv/bin/python")
    if not os.path.exists(vcm):
        sys.exit(f"{vcm} not found: run `cargo build --release` first")
    mi.set_variant(variant)
    return mi, np


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("scene", help="a Mitsuba 3 XML file")
    parser.add_argument("--resolution", default="128", help="film size, N (square) or WxH [128]")
    parser.add_argument("--spp", type=int, default=64, help="samples per pixel of each render [64]")
    parser.add_argument("--seeds", type=int, default=6, help="renders per renderer [6]")
    parser.add_argument("--variant", default="llvm_ad_rgb", help="Mitsuba variant [llvm_ad_rgb]")
    parser.add_argument("--vcm", default=os.path.join(ROOT, "target", "release", "vcm"))
    parser.add_argument("--emitter-threshold", type=float, default=5.0,
                        help="a pixel whose mean (sum of channels) exceeds this sees an emitter [5]")
    parser.add_argument("--extra", default="", help="extra arguments for `vcm render` (one string)")
    parser.add_argument("--mitsuba-sampler", default=None,
                        help="render Mitsuba with this sampler type instead of the file's "
                             "(independent, stratified, multijitter, orthogonal, ldsampler)")
    args = parser.parse_args()
    mi, np = import_mitsuba(args.vcm, args.variant)
    width, height = (int(v) for v in (args.resolution.split("x") * 2)[:2])
    scene_file = args.scene
    if args.mitsuba_sampler:
        # A copy of the file with its sampler's type replaced; its own folder stays on the
        # resolver's path for meshes and textures.
        text = open(args.scene).read()
        pattern = r'<sampler\s+type="[^"]*"'
        swapped = re.sub(pattern, f'<sampler type="{args.mitsuba_sampler}"', text, count=1)
        if not re.search(pattern, text):
            sys.exit(f"{args.scene}: no <sampler type=...> to replace")
        mi.file_resolver().prepend(os.path.dirname(os.path.abspath(args.scene)))
        scene_file = os.path.join(tempfile.mkdtemp(), os.path.basename(args.scene))
        with open(scene_file, "w") as f:
            f.write(swapped)
    theirs = []
    for seed in range(1, args.seeds + 1):
        scene = mi.load_file(scene_file, spp=args.spp)
        film = mi.traverse(scene.sensors()[0].film())
        film["size"] = [width, height]
        film.update()
        theirs.append(np.array(mi.render(scene, seed=seed), dtype=np.float64)[..., :3])
    theirs = np.array(theirs)
    ours = []
    with tempfile.TemporaryDirectory() as tmp:
        for seed in range(1, args.seeds + 1):
            out = os.path.join(tmp, f"pt{seed}.pfm")
            command = [args.vcm, "render", "--scene", args.scene, "-a", "pt", "-i", str(args.spp),
                       "-r", f"{width}x{height}", "--seed", str(seed), "-o", out, "--quiet"] + args.extra.split()
            subprocess.run(command, check=True, stdout=subprocess.DEVNULL)
            ours.append(read_pfm(out, np))
    ours = np.array(ours)
    emitters = dilate(theirs.mean(axis=0).sum(axis=2) > args.emitter_threshold, 4, np)
    sampler = f", Mitsuba's sampler {args.mitsuba_sampler}" if args.mitsuba_sampler else ""
    print(f"{args.scene}: {width}x{height}, {args.spp} spp, {args.seeds} seeds{sampler}; relative variance Σvar/Σmean²")
    print("| pixels | count | Mitsuba 3 `path` | ours `pt` | ours / Mitsuba |")
    print("|---|---:|---:|---:|---:|")
    for name, mask in [("all", np.ones_like(emitters)), ("seeing an emitter", emitters), ("the rest", ~emitters)]:
        if not mask.any():
            continue
        r_theirs, _ = relative_variance(theirs, mask, np)
        r_ours, _ = relative_variance(ours, mask, np)
        print(f"| {name} | {int(mask.sum())} | {r_theirs:.3g} | {r_ours:.3g} | {r_ours / r_theirs:.2f} |")
    ratio = ours.mean(axis=(0, 1, 2)) / theirs.mean(axis=(0, 1, 2))
    print("image mean ratio ours / Mitsuba per channel: " + ", ".join(f"{r:.4f}" for r in ratio))


if __name__ == "__main__":
    main()
