#!/bin/bash
# Paired timing of two builds on a noisy machine: OLD and NEW run `vcm bench` at the same time,
# one thread each, pinned to cores 0 and 1 (swapped every other round), so that whatever else
# the host does slows both alike. Prints, per round, the mean ms per iteration of each and the
# ratio NEW / OLD, then the median ratio. Needs two cores and `taskset` (util-linux).
#
# Usage: scripts/paired-bench.sh ROUNDS OLD_VCM NEW_VCM [vcm bench arguments...]
#   e.g. scripts/paired-bench.sh 6 ./vcm-old target/release/vcm -a vcm -s 1 -i 6
# (docs/performance.md, "Prefetching the merge queries").
set -euo pipefail
rounds=$1; old=$2; new=$3; shift 3
args=("$@")
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
# The bench's last line; its third column is the mean ms per iteration.
run() { taskset -c "$1" "$2" bench "${args[@]}" --threads 1 2>&1 | tail -1 | awk '{print $3}'; }
ratios=()
for round in $(seq "$rounds"); do
  if [ $((round % 2)) = 1 ]; then c_old=0; c_new=1; else c_old=1; c_new=0; fi
  run $c_old "$old" >"$out/old" &
  run $c_new "$new" >"$out/new"
  wait
  o=$(cat "$out/old"); n=$(cat "$out/new")
  r=$(awk -v o="$o" -v n="$n" 'BEGIN { printf "%.3f", n / o }')
  ratios+=("$r")
  echo "round $round: old $o ms, new $n ms, new/old $r"
done
printf '%s\n' "${ratios[@]}" | sort -n | awk '{ v[NR] = $1 } END { m = (NR % 2) ? v[(NR + 1) / 2] : (v[NR / 2] + v[NR / 2 + 1]) / 2; printf "median new/old %.3f over %d rounds\n", m, NR }'
