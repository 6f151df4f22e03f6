#!/bin/bash
# Rays per second of the renderer at an earlier commit against this checkout's, on scene files:
# `vcm bench --accel -s FILE --threads 1` (2^20 incoherent closest-hit rays and shadow rays from
# points on visible surfaces, one thread), the two builds alternating for ROUNDS rounds. Prints
# every row, then per scene the median of each build's closest-hit and shadow rates, their ratio
# (this checkout / BASE), and the median of the rounds' own ratios. Issue #13 item 4 compares
# against the commit of the day the issue was filed, 288e7a1 (docs/bvh.md, "Against the
# renderer of the issue's date").
#
# Usage: scripts/accel-history.sh [--paired] BASE ROUNDS SCENE_FILE...
#   e.g. scripts/accel-history.sh 288e7a1 3 ../shared/scenes/mitsuba/matpreview/matpreview.xml
# BASE is built once in a temporary worktree (its target directory kept under
# target/accel-history/, so a second run does not rebuild it); this checkout with `cargo build
# --release -p vcm`. Run it on an otherwise idle machine.
# --paired runs the two builds at the same time, pinned to cores 0 and 1 (swapped every other
# round, as scripts/paired-bench.sh does), so that a slow spell of the host slows both: on a
# shared virtual machine the host's speed drifts between sequential runs by more than the
# difference measured. Each build then has one core, and they share the last-level cache and
# the memory bandwidth. Needs two cores and `taskset`.
set -euo pipefail
paired=0
if [ "${1:-}" = --paired ]; then paired=1; shift; fi
[ $# -ge 3 ] || { sed -n '2,18p' "$0"; exit 2; }
base=$(git rev-parse --short "$1"); rounds=$2; shift 2
root=$(cd "$(dirname "$0")/.." && pwd)
cache=$root/target/accel-history/$base
tree=$(mktemp -d); out=$(mktemp)
trap 'git -C "$root" worktree remove --force "$tree" 2>/dev/null || true; rm -rf "$tree" "$out" "$out.old"' EXIT
if [ ! -x "$cache/release/vcm" ]; then
  git -C "$root" worktree add -q --detach "$tree" "$base"
  (cd "$tree" && CARGO_TARGET_DIR=$cache cargo build --release -q -p vcm)
fi
(cd "$root" && cargo build --release -q -p vcm)
old=$cache/release/vcm; new=$root/target/release/vcm
# The scene's row of `vcm bench --accel` with build $1 on core $3 (any core when $3 is empty):
# name, primitives, build s, closest 1T, closest nT, shadow 1T, shadow nT.
row() {
  local pin=(); [ -n "$3" ] && pin=(taskset -c "$3")
  "${pin[@]}" "$1" bench --accel -s "$2" --threads 1 2>&1 | grep -E "^$(basename "$2") " | head -1 || true
}
record() {  # round, build name, scene, row
  [ -n "$4" ] || { echo "error: no result row for $3 from the $2 build" >&2; exit 1; }
  echo "round $1 $2 $4"
  echo "$(basename "$3") $2 $(echo "$4" | awk '{print $4, $6}')" >>"$out"
}
for round in $(seq "$rounds"); do
  for scene in "$@"; do
    if [ $paired = 1 ]; then
      if [ $((round % 2)) = 1 ]; then c_old=0; c_new=1; else c_old=1; c_new=0; fi
      row "$old" "$scene" $c_old >"$out.old" &
      new_row=$(row "$new" "$scene" $c_new)
      wait
      record "$round" old "$scene" "$(cat "$out.old")"
      record "$round" new "$scene" "$new_row"
    else
      record "$round" old "$scene" "$(row "$old" "$scene" "")"
      record "$round" new "$scene" "$(row "$new" "$scene" "")"
    fi
  done
done
echo
mode=alternating; [ $paired = 1 ] && mode=paired
echo "medians over $rounds $mode rounds, Mrays/s on one thread (BASE $base / this checkout $(git -C "$root" rev-parse --short HEAD)):"
for scene in "$@"; do
  name=$(basename "$scene")
  python3 - "$out" "$name" <<'PY'
import statistics, sys
rows = [l.split() for l in open(sys.argv[1]) if l.split()[0] == sys.argv[2]]
med = lambda build, col: statistics.median(float(r[col]) for r in rows if r[1] == build)
c0, c1, s0, s1 = med("old", 2), med("new", 2), med("old", 3), med("new", 3)
# Rows come in pairs, old then new, one pair per round: the median of the rounds' own ratios.
pairs = list(zip(rows[0::2], rows[1::2]))
ratio = lambda col: statistics.median(float(n[col]) / float(o[col]) for o, n in pairs)
print(f"{sys.argv[2]:<24} closest {c0:.2f} -> {c1:.2f} ({c1 / c0:.2f}x, rounds' median {ratio(2):.2f}x)   "
      f"shadow {s0:.2f} -> {s1:.2f} ({s1 / s0:.2f}x, rounds' median {ratio(3):.2f}x)")
PY
done
