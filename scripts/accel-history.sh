#!/bin/bash
# Rays per second of the renderer at an earlier commit against this checkout's, on scene files:
# `vcm bench --accel -s FILE --threads 1` (2^20 incoherent closest-hit rays and shadow rays from
# points on visible surfaces, one thread), the two builds alternating for ROUNDS rounds. Prints
# every row, then per scene the median of each build's closest-hit and shadow rates and their
# ratio (this checkout / BASE). Issue #13 item 4 compares against the commit of the day the issue
# was filed, 288e7a1 (docs/bvh.md, "Against the renderer of the issue's date").
#
# Usage: scripts/accel-history.sh BASE ROUNDS SCENE_FILE...
#   e.g. scripts/accel-history.sh 288e7a1 3 ../shared/scenes/mitsuba/matpreview/matpreview.xml
# BASE is built once in a temporary worktree (its target directory kept under
# target/accel-history/, so a second run does not rebuild it); this checkout with `cargo build
# --release -p vcm`. Run it on an otherwise idle machine.
set -euo pipefail
[ $# -ge 3 ] || { sed -n '2,13p' "$0"; exit 2; }
base=$(git rev-parse --short "$1"); rounds=$2; shift 2
root=$(cd "$(dirname "$0")/.." && pwd)
cache=$root/target/accel-history/$base
tree=$(mktemp -d); out=$(mktemp)
trap 'git -C "$root" worktree remove --force "$tree" 2>/dev/null || true; rm -rf "$tree" "$out"' EXIT
if [ ! -x "$cache/release/vcm" ]; then
  git -C "$root" worktree add -q --detach "$tree" "$base"
  (cd "$tree" && CARGO_TARGET_DIR=$cache cargo build --release -q -p vcm)
fi
(cd "$root" && cargo build --release -q -p vcm)
old=$cache/release/vcm; new=$root/target/release/vcm
for round in $(seq "$rounds"); do
  for scene in "$@"; do
    for build in old new; do
      bin=$old; [ $build = new ] && bin=$new
      # The scene's row: name, primitives, build s, closest 1T, closest nT, shadow 1T, shadow nT.
      row=$("$bin" bench --accel -s "$scene" --threads 1 2>&1 | grep -E "^$(basename "$scene") " | head -1)
      [ -n "$row" ] || { echo "error: no result row for $scene from $bin" >&2; exit 1; }
      echo "round $round $build $row"
      echo "$(basename "$scene") $build $(echo "$row" | awk '{print $4, $6}')" >>"$out"
    done
  done
done
echo
echo "medians over $rounds rounds, Mrays/s on one thread (BASE $base / this checkout $(git -C "$root" rev-parse --short HEAD)):"
for scene in "$@"; do
  name=$(basename "$scene")
  python3 - "$out" "$name" <<'PY'
import statistics, sys
rows = [l.split() for l in open(sys.argv[1]) if l.split()[0] == sys.argv[2]]
med = lambda build, col: statistics.median(float(r[col]) for r in rows if r[1] == build)
c0, c1, s0, s1 = med("old", 2), med("new", 2), med("old", 3), med("new", 3)
print(f"{sys.argv[2]:<24} closest {c0:.2f} -> {c1:.2f} ({c1 / c0:.2f}x)   shadow {s0:.2f} -> {s1:.2f} ({s1 / s0:.2f}x)")
PY
done
