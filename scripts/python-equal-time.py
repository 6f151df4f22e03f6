#!/usr/bin/env python3
"""Equal-time comparison of pt, bpt and vcm through the vcm Python module: relative MSE against
render time, log-log, saved as a figure (docs/python.md shows it).

    python3 scripts/python-equal-time.py --scene cornell-sun --seconds 30 \
        --output docs/images/python-equal-time.png

The reference is a vcm render of --reference-seconds (default: 4x --seconds) with another seed,
or an image file given with --reference. Times are the sessions' own (Session.seconds: rendering
only; measuring the error is not counted). Needs matplotlib.
"""

import argparse

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

import vcm  # noqa: E402


def convergence(scene, algorithm, seconds, reference, resolution):
    """(seconds, relMSE) after iterations 1, 2, 4, 8, ... and at the end of the budget."""
    session = vcm.Session(scene, algorithm=algorithm, resolution=resolution, seed=1)
    points, next_measure = [], 1
    while session.seconds < seconds:
        session.step()
        if session.iterations >= next_measure or session.seconds >= seconds:
            points.append((session.seconds, vcm.compare(session.image(), reference)["relmse"]))
            next_measure *= 2
    return points, session.iterations


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--scene", default="cornell-sun", help="built-in scene or scene file")
    parser.add_argument("--seconds", type=float, default=30.0, help="render time per algorithm")
    parser.add_argument("--reference", help="reference image (default: a longer vcm render)")
    parser.add_argument("--reference-seconds", type=float, help="time of the reference render")
    parser.add_argument("--resolution", type=int, nargs=2, metavar=("W", "H"), help="image size")
    parser.add_argument("--algorithms", nargs="+", default=["pt", "bpt", "vcm"])
    parser.add_argument("--output", default="python-equal-time.png")
    args = parser.parse_args()

    scene = vcm.load_file(args.scene)
    resolution = tuple(args.resolution) if args.resolution else None
    if args.reference:
        reference = vcm.read(args.reference)
    else:
        budget = args.reference_seconds or 4 * args.seconds
        reference = vcm.render(scene, algorithm="vcm", time=budget, resolution=resolution, seed=1000)

    figure, axes = plt.subplots(figsize=(6, 4.2))
    for algorithm in args.algorithms:
        points, iterations = convergence(scene, algorithm, args.seconds, reference, resolution)
        times, errors = zip(*points)
        axes.loglog(times, errors, marker="o", markersize=3, label=f"{algorithm} ({iterations} it)")
        print(f"{algorithm}: {iterations} iterations in {times[-1]:.1f} s, relMSE {errors[-1]:.3e}")
    axes.set_xlabel("render time [s]")
    axes.set_ylabel("relative MSE")
    axes.set_title(f"{scene.name}: equal time, {args.seconds:g} s each")
    axes.grid(True, which="both", alpha=0.3)
    axes.legend()
    figure.tight_layout()
    figure.savefig(args.output, dpi=120)
    print(f"wrote {args.output}")


if __name__ == "__main__":
    main()
