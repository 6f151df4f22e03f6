#!/bin/bash
# Bit identity of images between two builds, for changes meant to be pure speed: renders a fixed
# list of (scene, algorithm, options) cases with both binaries and `cmp`s the EXRs.
#
# Usage: scripts/image-identity.sh BASE_VCM NEW_VCM OUT_DIR
#
# Cases: the built-in scenes 0-3 with all six algorithms, vcm --spectral, vcm with one and two
# threads and --memory-efficient; the repository's scene files (scenes/*.xml, *.pbrt) with pt
# and vcm; and, when ../shared/scenes/mitsuba is beside the repository, Mitsuba's matpreview
# (pt, bpt, vcm, pt --spectral), Cornell box (pt, bpt) and veach-mis (pt). Small images and few
# iterations: this checks identity, not quality. Exits 1 when a pair differs or a render fails.
set -u
base=$1; new=$2; out=$3
root=$(cd "$(dirname "$0")/.." && pwd)
shared=$root/../shared/scenes/mitsuba
mkdir -p "$out"
cases=()
for s in 0 1 2 3; do
  for a in pt lt bpt ppm bpm vcm; do cases+=("scene$s-$a|--scene $s -a $a -r 64x64 -i 3"); done
  cases+=("scene$s-vcm-spectral|--scene $s -a vcm --spectral -r 64x64 -i 3")
done
cases+=("scene1-vcm-t1|--scene 1 -a vcm -r 64x64 -i 3 --threads 1")
cases+=("scene1-vcm-t2|--scene 1 -a vcm -r 64x64 -i 3 --threads 2")
cases+=("scene1-vcm-memory-efficient|--scene 1 -a vcm -r 64x64 -i 3 --memory-efficient")
for f in "$root"/scenes/*.xml "$root"/scenes/*.pbrt; do
  name=$(basename "$f"); name=${name%.*}
  for a in pt vcm; do cases+=("$name-$a|--scene $f -a $a -r 64x48 -i 2"); done
done
if [ -d "$shared" ]; then
  mp=$shared/matpreview/matpreview.xml; cb=$shared/cornell-box/cornell_box.xml
  for a in pt bpt vcm; do cases+=("matpreview-$a|--scene $mp -a $a -r 120x90 -i 2"); done
  cases+=("matpreview-pt-spectral|--scene $mp -a pt --spectral -r 120x90 -i 2")
  for a in pt bpt; do cases+=("cornell_box-$a|--scene $cb -a $a -r 64x64 -i 4"); done
  cases+=("veach-mis-pt|--scene $shared/veach-mis/veach_mis_path.xml -a pt -r 96x64 -i 2")
else
  echo "note: $shared is missing; Mitsuba's scenes are not compared"
fi
fail=0; n=0
for c in "${cases[@]}"; do
  name=${c%%|*}; args=${c#*|}
  for b in base new; do
    bin=$base; [ $b = new ] && bin=$new
    # shellcheck disable=SC2086
    "$bin" render $args --seed 7 --quiet -o "$out/$b-$name.exr" > "$out/$b-$name.log" 2>&1 \
      || { echo "render failed: $b $name (see $out/$b-$name.log)"; fail=1; }
  done
  n=$((n+1))
  if cmp -s "$out/base-$name.exr" "$out/new-$name.exr"; then echo "identical: $name"; else echo "DIFFER: $name"; fail=1; fi
done
echo "compared $n pairs, fail=$fail"
exit $fail
