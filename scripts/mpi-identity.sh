#!/usr/bin/env bash
# Compares `mpirun -np 1/2/3 vcm render ...` (a binary built with --features mpi) with the
# single-process image of a binary built without it, byte for byte (cmp of the EXRs), for pt,
# vcm, spectral vcm, a scene file and a --time run (whose iteration count the single process
# then renders); then the batch route: `vcm render --slice K/N` + `vcm merge` against one
# `vcm render --sums fixed` (image and checkpoint cmp-identical), with slices rendered by the
# single-process binary and by `mpirun -np 2`. Ends with a "test result:" line in cargo's form
# for .ci/run's total.
#
# Usage: scripts/mpi-identity.sh SINGLE_BIN MPI_BIN
set -uo pipefail
single=$1
mpi=$2
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
# As root OpenMPI refuses to start without these; --oversubscribe allows more ranks than cores.
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
mpirun_=(mpirun --oversubscribe)
passed=0
failed=0

# result STATUS NAME LOG: counts test NAME as passed when STATUS is 0, else as failed and shows LOG.
result() {
    if [ "$1" -eq 0 ]; then
        echo "test $2 ... ok"
        passed=$((passed + 1))
    else
        echo "test $2 ... FAILED"
        cat "$3"
        failed=$((failed + 1))
    fi
}

# check NAME ARGS...: one single-process render, then 1, 2 and 3 ranks with the same arguments.
check() {
    local name=$1
    shift
    "$single" render "$@" --quiet --threads 1 -o "$out/$name-single.exr" 2>"$out/$name-single.log" || {
        echo "FAIL $name: the single-process render failed"; cat "$out/$name-single.log"; failed=$((failed + 1)); return; }
    for n in 1 2 3; do
        "${mpirun_[@]}" -np "$n" "$mpi" render "$@" --quiet --threads 1 -o "$out/$name-$n.exr" \
            >"$out/$name-$n.log" 2>&1 && cmp -s "$out/$name-single.exr" "$out/$name-$n.exr"
        result $? "$name with $n ranks" "$out/$name-$n.log"
    done
}

# pt, bpt and vcm on each of the four Cornell scenes.
for scene in 0 1 2 3; do
    check "pt-$scene" --scene "$scene" --algorithm pt --resolution 48x36 --iterations 7 --seed 3
    check "bpt-$scene" --scene "$scene" --algorithm bpt --resolution 48x36 --iterations 5 --seed 3
    check "vcm-$scene" --scene "$scene" --algorithm vcm --resolution 48x36 --iterations 7 --seed 3
done
check spectral-vcm --scene 1 --algorithm vcm --spectral --resolution 48x36 --iterations 5 --seed 3
# The scene file comes from ../shared: missing, it is a visible skip (a failure under CI=true).
shared_missing() {
    if [ "${CI:-}" = true ]; then
        echo "test $1 ... FAILED (../shared/scenes/mitsuba/cbox-classic/cbox.xml is missing)"; failed=$((failed + 1))
    else
        echo "test $1 ... SKIPPED (no ../shared beside the clone)"
    fi
}
if [ ! -f ../shared/scenes/mitsuba/cbox-classic/cbox.xml ]; then
    shared_missing scene-file
else
    check scene-file --scene ../shared/scenes/mitsuba/cbox-classic/cbox.xml --algorithm vcm --resolution 40x40 --iterations 4
fi

# --time: whole rounds; the summary line names the iteration count, which one process renders.
for n in 2 3; do
    name=time-$n
    "${mpirun_[@]}" -np "$n" "$mpi" render --scene 1 --algorithm vcm --resolution 32x24 --time 0.5 --threads 1 \
        --quiet -o "$out/$name.exr" >"$out/$name.log" 2>&1
    iterations=$(grep -o '[0-9]* iterations' "$out/$name.log" | head -1 | cut -d' ' -f1)
    [ -n "$iterations" ] && [ $((iterations % n)) -eq 0 ] && grep -q "x $n ranks" "$out/$name.log" &&
        "$single" render --scene 1 --algorithm vcm --resolution 32x24 --iterations "$iterations" --threads 1 --quiet \
            -o "$out/$name-single.exr" 2>/dev/null && cmp -s "$out/$name.exr" "$out/$name-single.exr"
    result $? "--time with $n ranks (${iterations:-no} iterations)" "$out/$name.log"
done

# check_slices NAME N ARGS...: N slices merged equal one process with --sums fixed (image and
# checkpoint); the slices are rendered by the single binary, or by `mpirun -np 2` when
# SLICE_RANKS=2.
check_slices() {
    local name=$1 count=$2
    shift 2
    "$single" render "$@" --sums fixed --quiet --threads 1 -o "$out/$name-fixed.exr" \
        --checkpoint "$out/$name-fixed.ckpt" 2>"$out/$name-fixed.log" || {
        echo "FAIL $name: the single-process render failed"; cat "$out/$name-fixed.log"; failed=$((failed + 1)); return; }
    local parts=() k
    for ((k = 0; k < count; k++)); do
        if [ "${SLICE_RANKS:-1}" -gt 1 ]; then
            "${mpirun_[@]}" -np "$SLICE_RANKS" "$mpi" render "$@" --slice "$k/$count" --quiet --threads 1 \
                -o "$out/$name-part.exr" --checkpoint "$out/$name-part-$k.ckpt" >>"$out/$name-parts.log" 2>&1
        else
            "$single" render "$@" --slice "$k/$count" --quiet --threads 1 -o "$out/$name-part.exr" \
                --checkpoint "$out/$name-part-$k.ckpt" >>"$out/$name-parts.log" 2>&1
        fi
        parts+=("$out/$name-part-$k.ckpt")
    done
    "$single" merge "${parts[@]}" -o "$out/$name-merged.exr" --checkpoint "$out/$name-merged.ckpt" \
        >>"$out/$name-parts.log" 2>&1 && cmp -s "$out/$name-fixed.exr" "$out/$name-merged.exr" &&
        cmp -s "$out/$name-fixed.ckpt" "$out/$name-merged.ckpt"
    result $? "$name: $count slices merged (ranks per slice: ${SLICE_RANKS:-1})" "$out/$name-parts.log"
}

for scene in 0 1 2 3; do
    check_slices "slices-pt-$scene" 3 --scene "$scene" --algorithm pt --resolution 48x36 --iterations 7 --seed 3
    check_slices "slices-bpt-$scene" 2 --scene "$scene" --algorithm bpt --resolution 48x36 --iterations 5 --seed 3
    check_slices "slices-vcm-$scene" 4 --scene "$scene" --algorithm vcm --resolution 48x36 --iterations 7 --seed 3
done
check_slices slices-spectral-vcm 3 --scene 1 --algorithm vcm --spectral --resolution 48x36 --iterations 5 --seed 3
if [ ! -f ../shared/scenes/mitsuba/cbox-classic/cbox.xml ]; then
    shared_missing slices-scene-file
else
    check_slices slices-scene-file 2 --scene ../shared/scenes/mitsuba/cbox-classic/cbox.xml --algorithm vcm \
        --resolution 40x40 --iterations 4
fi
SLICE_RANKS=2 check_slices slices-vcm-on-ranks 2 --scene 1 --algorithm vcm --resolution 48x36 --iterations 6 --seed 3

# A missing slice is an error naming it (exit code 2, no image).
"$single" merge "$out/slices-pt-1-part-0.ckpt" "$out/slices-pt-1-part-2.ckpt" -o "$out/missing.exr" >"$out/missing.log" 2>&1
code=$?
[ "$code" -eq 2 ] && grep -q "slices missing: 1/3" "$out/missing.log" && [ ! -f "$out/missing.exr" ]
result $? "a missing slice is named (exit code $code)" "$out/missing.log"

# A scene that fails to load ends every rank with exit code 2 (no hang: bounded by timeout).
printf '<scene version="3.0.0">\n<shape type="nonsense"/>\n' >"$out/bad.xml"
timeout 120 "${mpirun_[@]}" -np 2 "$mpi" render --scene "$out/bad.xml" --quiet -o "$out/bad.exr" >"$out/bad.log" 2>&1
code=$?
# Which condition failed goes into the log shown on failure (a failure in CI on 2026-12-02 passed
# when rerun 36 times; the next one should say which part it was).
problems=()
[ "$code" -ne 0 ] && [ "$code" -ne 124 ] || problems+=("(check: exit code $code)")
grep -q "error: .*bad.xml" "$out/bad.log" || problems+=("(check: no error line naming bad.xml when mpirun returned)")
[ ! -f "$out/bad.exr" ] || problems+=("(check: an image was written)")
[ ${#problems[@]} -eq 0 ] || printf '%s\n' "${problems[@]}" >>"$out/bad.log"
[ ${#problems[@]} -eq 0 ]
result $? "a bad scene ends every rank (exit code $code)" "$out/bad.log"

if [ "$failed" -eq 0 ]; then status=ok; else status=FAILED; fi
echo "test result: $status. $passed passed; $failed failed; (scripts/mpi-identity.sh)"
[ "$failed" -eq 0 ]
