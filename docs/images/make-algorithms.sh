#!/usr/bin/env bash
# Renders cornell-sun with the six algorithms at equal wall-clock time (the README picture).
# Usage: docs/images/make-algorithms.sh [SECONDS] [OUTDIR]
set -euo pipefail
seconds=${1:-30}
out=${2:-out/algorithms}
mkdir -p "$out"
cargo build --release --quiet
for a in pt lt ppm bpm bpt vcm; do
  target/release/vcm render --scene cornell-sun --algorithm "$a" --time "$seconds" --quiet -o "$out/$a.exr"
done
