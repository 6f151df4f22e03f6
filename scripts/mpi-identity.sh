#!/usr/bin/env bash
# Compares `mpirun -np 1/2/3 vcm render ...` (a binary built with --features mpi) with the
# single-process image of a binary built without it, byte for byte (cmp of the EXRs), for pt,
# vcm, spectral vcm, a scene file and a --time run (whose iteration count the single process
# then renders). Ends with a "test result:" line in cargo's form for .ci/run's total.
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

# check NAME ARGS...: one single-process render, then 1, 2 and 3 ranks with the same arguments.
check() {
    local name=$1
    shift
    "$single" render "$@" --quiet --threads 1 -o "$out/$name-single.exr" 2>"$out/$name-single.log" || {
        echo "FAIL $name: the single-process render failed"; cat "$out/$name-single.log"; failed=$((failed + 1)); return; }
    for n in 1 2 3; do
        if "${mpirun_[@]}" -np "$n" "$mpi" render "$@" --quiet --threads 1 -o "$out/$name-$n.exr" \
            >"$out/$name-$n.log" 2>&1 && cmp -s "$out/$name-single.exr" "$out/$name-$n.exr"; then
            echo "test $name with $n ranks ... ok"
            passed=$((passed + 1))
        else
            echo "test $name with $n ranks ... FAILED"
            cat "$out/$name-$n.log"
            failed=$((failed + 1))
        fi
    done
}

check pt --scene 1 --algorithm pt --resolution 48x36 --iterations 7 --seed 3
check vcm --scene 1 --algorithm vcm --resolution 48x36 --iterations 7 --seed 3
check spectral-vcm --scene 1 --algorithm vcm --spectral --resolution 48x36 --iterations 5 --seed 3
check bpt --scene 1 --algorithm bpt --resolution 48x36 --iterations 5 --seed 3
if [ -f ../shared/scenes/mitsuba/cbox-classic/cbox.xml ]; then
    check scene-file --scene ../shared/scenes/mitsuba/cbox-classic/cbox.xml --algorithm vcm --resolution 40x40 --iterations 4
fi

# --time: whole rounds; the summary line names the iteration count, which one process renders.
for n in 2 3; do
    name=time-$n
    "${mpirun_[@]}" -np "$n" "$mpi" render --scene 1 --algorithm vcm --resolution 32x24 --time 0.5 --threads 1 \
        --quiet -o "$out/$name.exr" >"$out/$name.log" 2>&1
    iterations=$(grep -o '[0-9]* iterations' "$out/$name.log" | head -1 | cut -d' ' -f1)
    if [ -n "$iterations" ] && [ $((iterations % n)) -eq 0 ] && grep -q "x $n ranks" "$out/$name.log" &&
        "$single" render --scene 1 --algorithm vcm --resolution 32x24 --iterations "$iterations" --threads 1 --quiet \
            -o "$out/$name-single.exr" 2>/dev/null && cmp -s "$out/$name.exr" "$out/$name-single.exr"; then
        echo "test --time with $n ranks ($iterations iterations) ... ok"
        passed=$((passed + 1))
    else
        echo "test --time with $n ranks ... FAILED"
        cat "$out/$name.log"
        failed=$((failed + 1))
    fi
done

# A scene that fails to load ends every rank with exit code 2 (no hang: bounded by timeout).
printf '<scene version="3.0.0">\n<shape type="nonsense"/>\n' >"$out/bad.xml"
timeout 120 "${mpirun_[@]}" -np 2 "$mpi" render --scene "$out/bad.xml" --quiet -o "$out/bad.exr" >"$out/bad.log" 2>&1
code=$?
if [ "$code" -ne 0 ] && [ "$code" -ne 124 ] && grep -q "^error: " "$out/bad.log" && [ ! -f "$out/bad.exr" ]; then
    echo "test a bad scene ends every rank ... ok"
    passed=$((passed + 1))
else
    echo "test a bad scene ends every rank ... FAILED (exit code $code)"
    cat "$out/bad.log"
    failed=$((failed + 1))
fi

if [ "$failed" -eq 0 ]; then status=ok; else status=FAILED; fi
echo "test result: $status. $passed passed; $failed failed; (scripts/mpi-identity.sh)"
[ "$failed" -eq 0 ]
