#!/bin/bash
# Renders the Mitsuba 3 test-suite scenes of the textured lights and compares them with
# Mitsuba's references (per-pixel Z-test with both variance images; channel means).
# Usage: scripts/lights-suite.sh SUITE_SCENES_DIR OUT_DIR ALGORITHM ITERATIONS SCENE...
#   SCENE is relative to SUITE_SCENES_DIR, e.g. spot_light/test_spot_direct.xml; the
#   reference is <dir>/refs/<name without _direct/_ptracer>_ref_rgb.exr (+ _var.exr).
# Example: scripts/lights-suite.sh ../scratch/mitsuba-data/tests/scenes /tmp/suite pt 8192 \
#            spot_light/test_spot_direct.xml
set -u
vcm=${VCM:-target/release/vcm}
suite=$1; out=$2; algorithm=$3; iterations=$4; shift 4
mkdir -p "$out"
for scene in "$@"; do
  dir=$(dirname "$scene"); name=$(basename "$scene" .xml)
  base=${name%_direct}; base=${base%_ptracer}; base=${base%_path}
  image="$out/$base-$algorithm"
  if ! "$vcm" render --scene "$suite/$scene" -a "$algorithm" -i "$iterations" \
      --variance "$image-var.exr" -o "$image.exr" > "$image.log" 2>&1; then
    echo "== $base $algorithm: render failed"; tail -2 "$image.log"; continue
  fi
  echo "== $base $algorithm $iterations iterations"
  "$vcm" compare "$image.exr" "$suite/$dir/refs/${base}_ref_rgb.exr" \
    --variance-a "$image-var.exr" --variance-b "$suite/$dir/refs/${base}_ref_rgb_var.exr" | tail -6
done
