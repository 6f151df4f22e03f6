#!/bin/bash
# relMSE of spectral VCM (K wavelength groups; or another ALGORITHM) against RGB at equal
# iterations on built-in scene 1 (issue #11): 1024-iteration references of each mode (seed 100;
# spectral with K = 16, which only the merging algorithms use),
# then SEEDS renders of 16 iterations at 128² per mode, each compared with its own mode's
# reference by `vcm compare`; prints the per-seed relMSEs and the ratio of the means.
# Usage: scripts/spectral-relmse.sh [SEEDS=16] [K=4] [OUT_DIR=/tmp/spectral-relmse] [ALGORITHM=vcm]
# (Counts only: the equal-time ratio multiplies this by scripts/spectral-cost.py's CPU ratio.)
set -eu
seeds=${1:-16}; k=${2:-4}; out=${3:-/tmp/spectral-relmse}; a=${4:-vcm}
cargo build --release -q -p vcm -p render --example spectral_groups
e=target/release/examples/spectral_groups; v=target/release/vcm
mkdir -p "$out"
[ -f "$out/ref_rgb.exr" ] || $e 1 $a 1024 128 100 rgb 1 "$out/ref_rgb.exr" > /dev/null
[ -f "$out/ref_spectral.exr" ] || $e 1 $a 1024 128 100 spectral 16 "$out/ref_spectral.exr" > /dev/null
relmse() { $v compare "$1" "$2" | sed -n 's/.*relative MSE: *\([0-9.eE+-]*\).*/\1/p' | head -1; }
sum_r=0; sum_s=0
for s in $(seq 1 "$seeds"); do
  $e 1 $a 16 128 "$s" rgb 1 "$out/rgb-$s.exr" > /dev/null
  $e 1 $a 16 128 "$s" spectral "$k" "$out/spectral-$s.exr" > /dev/null
  r=$(relmse "$out/rgb-$s.exr" "$out/ref_rgb.exr"); p=$(relmse "$out/spectral-$s.exr" "$out/ref_spectral.exr")
  echo "seed $s: rgb $r spectral $p"
  sum_r=$(python3 -c "print($sum_r + $r)"); sum_s=$(python3 -c "print($sum_s + $p)")
done
python3 -c "print('mean relMSE: rgb %.5f, spectral %.5f, ratio %.4f' % ($sum_r / $seeds, $sum_s / $seeds, $sum_s / $sum_r))"
