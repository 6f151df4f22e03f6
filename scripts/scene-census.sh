#!/usr/bin/env bash
# Which scene files of a collection load and render (a 8x8 pt render of one iteration), and the
# first error of each that does not: `scripts/scene-census.sh DIR...` prints one line per file
# ("ok" or the error's first line) and a summary with the most frequent first errors.
# Used to count how many public Mitsuba 3 / pbrt-v4 scene files the renderer reads (issue #12);
# the collections are fetched, never committed. Needs target/release/vcm. Files that leave the
# sample count to the command line (`$spp` without a default) get `-D spp=4`, as Mitsuba's
# `-Dspp=4`. The last line counts the files that need no unsupported media feature and no
# polarization (issue #12's measure: at least 90 % of them must load).
set -uo pipefail
vcm="$(dirname "$0")/../target/release/vcm"
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
total=0
ok=0
excluded=0
declare -A reasons
while IFS= read -r -d '' file; do
    # Fragments that other files include live in include/, fragments/ or common/.
    case "$file" in
        */include/* | */fragments/* | */common/*) continue ;;
    esac
    total=$((total + 1))
    if message=$(timeout 120 "$vcm" render --scene "$file" -D spp=4 -a pt -i 1 -r 8x8 --quiet -o "$out/x.exr" 2>&1 >/dev/null); then
        ok=$((ok + 1))
        echo "ok    $file"
    else
        first=$(printf '%s\n' "$message" | grep -m1 -i 'error' || printf '%s\n' "$message" | head -1)
        echo "FAIL  $file: $first"
        if printf '%s' "$first" | grep -Eq "<medium>|^error: [^ ]+ medium '|issue #15|'(pplastic|polarizer|measured_polarized|hair)'|integrator 'stokes'"; then
            excluded=$((excluded + 1))
        fi
        # Group by the message without the file position.
        key=$(printf '%s' "$first" | sed -E 's/^error: //; s/^[^ ]+:[0-9]+:[0-9]+: //; s/ \(searched.*//; s/; the <path>.*//; s/"[^"]*"/"…"/g; s/'"'"'[^'"'"']*'"'"'/'"'"'…'"'"'/g' | cut -c1-100)
        reasons["$key"]=$(( ${reasons["$key"]:-0} + 1 ))
    fi
done < <(find "$@" \( -name '*.xml' -o -name '*.pbrt' \) -print0 | sort -z)
echo
echo "$ok of $total scene files load and render"
needing_none=$((total - excluded))
echo "$ok of $needing_none files that need no unsupported media feature and no polarization load ($((100 * ok / needing_none)) %)"
for key in "${!reasons[@]}"; do
    printf '%4d  %s\n' "${reasons[$key]}" "$key"
done | sort -rn | head -25
