#!/bin/bash
# Surface-only bit identity of the merging algorithms: renders the built-in scenes 0-3 with
# vcm, bpm, ppm and vcm --spectral (96x96, 4 iterations, seed 7) with two binaries and `cmp`s
# the EXRs. Usage: scripts/surface-identity.sh BASE_VCM NEW_VCM OUT_DIR
set -u
base=$1; new=$2; out=$3
mkdir -p "$out"
fail=0; n=0
for s in 0 1 2 3; do
  for a in vcm bpm ppm vcm-spectral; do
    alg=${a%-spectral}; extra=()
    [ "$a" = vcm-spectral ] && extra=(--spectral)
    for b in base new; do
      bin=$base; [ $b = new ] && bin=$new
      "$bin" render --scene $s -a "$alg" "${extra[@]}" -r 96x96 -i 4 --seed 7 -o "$out/$b-$s-$a.exr" > /dev/null 2>&1 \
        || { echo "render failed: $b scene $s $a"; fail=1; }
    done
    n=$((n+1))
    if cmp -s "$out/base-$s-$a.exr" "$out/new-$s-$a.exr"; then echo "identical: scene $s $a"; else echo "DIFFER: scene $s $a"; fail=1; fi
  done
done
echo "compared $n pairs, fail=$fail"
exit $fail
