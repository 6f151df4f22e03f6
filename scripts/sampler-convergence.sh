#!/bin/bash
# Does a sampler's render converge to the right image? Renders Mitsuba's Cornell box with `pt`
# at 64, 256 and 1,024 iterations for each `--sampler`, and prints each render's relative MSE
# against Mitsuba's reference (`vcm compare`, epsilon 0.01). With independent numbers it falls as
# 1/N; a sampler whose pixels converge to wrong values stops falling (docs/performance.md,
# "Stratified first vertices"). About 11 minutes on two cores.
#
# Usage: scripts/sampler-convergence.sh [VCM] [SHARED_SCENES]
#   VCM defaults to target/release/vcm; SHARED_SCENES to ../shared/scenes.
set -euo pipefail
vcm=${1:-target/release/vcm}
scenes=${2:-../shared/scenes}
dir="$scenes/mitsuba/cornell-box"
[ -f "$dir/cornell_box.xml" ] || { echo "$dir/cornell_box.xml is absent (give SHARED_SCENES)" >&2; exit 1; }
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
printf '%-12s %10s %12s\n' sampler iterations relMSE
for sampler in independent sobol; do
    for n in 64 256 1024; do
        "$vcm" render --scene "$dir/cornell_box.xml" -a pt -i "$n" --sampler "$sampler" \
            -o "$out/render.exr" --quiet > /dev/null 2> "$out/log" || { cat "$out/log" >&2; exit 1; }
        rel=$("$vcm" compare "$out/render.exr" "$dir/cbox_dict.exr" | awk '/relative MSE/ {print $3}')
        printf '%-12s %10d %12s\n' "$sampler" "$n" "$rel"
    done
done
