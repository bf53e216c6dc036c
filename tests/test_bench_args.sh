#!/usr/bin/env bash
# The granular benchmarks' command lines (README, Benchmarks: Granular piles, Hoppers, A cooling
# granular gas), as a user first tries them: `--help` prints what the script does and exits 0
# without running anything, and an argument the script cannot take is refused with exit 2 and
# one line, before any run (until 2026-11-30 bench-cooling.py ignored every argument and ran
# its minutes-long benchmark for --help; bench-hopper.sh and bench-granular.sh passed --help to
# nbep as the sphere count; bench-pile.py's --help cut its description at "e = 0.5 against").
# NBEP names a program that fails, so that any run a script starts shows.
# Run from anywhere; exit status 1 when a check fails.
. "$(dirname "$0")/lib.sh"
test_tmp bench_args
need_py h5py numpy
export NBEP=/bin/false OUT="$tmp/out"

for s in bench-hopper.sh bench-granular.sh; do
    timeout 20 sh scripts/$s --help >"$tmp/out.txt" 2>"$tmp/err.txt"
    rc=$?
    check "$s --help: exit 0 (got $rc), its usage line, nothing on stderr" \
        "[ $rc = 0 ] && grep -q '^  scripts/$s \[COUNT \[STEPS \[REPEATS\]\]\]' '$tmp/out.txt' &&
         [ ! -s '$tmp/err.txt' ]"
    for bad in 40x -n 0; do
        timeout 20 sh scripts/$s "$bad" >"$tmp/out.txt" 2>"$tmp/err.txt"
        rc=$?
        check "$s $bad: exit 2 (got $rc), one line, no run" \
            "[ $rc = 2 ] && [ \$(wc -l <'$tmp/err.txt') = 1 ] &&
             grep -q '^$s: COUNT, STEPS and REPEATS are positive integers (got .$bad.); --help' '$tmp/err.txt'"
    done
    timeout 20 sh scripts/$s 1 2 3 4 >"$tmp/out.txt" 2>"$tmp/err.txt"
    rc=$?
    check "$s with four arguments: exit 2 (got $rc), one line" \
        "[ $rc = 2 ] && [ \$(wc -l <'$tmp/err.txt') = 1 ]"
done

timeout 20 "$PY" scripts/bench-cooling.py --help >"$tmp/out.txt" 2>"$tmp/err.txt"
rc=$?
check "bench-cooling.py --help: exit 0 (got $rc), its settings, nothing run or made" \
    "[ $rc = 0 ] && grep -q '^Environment: NS' '$tmp/out.txt' && [ ! -s '$tmp/err.txt' ] &&
     [ ! -e '$tmp/out' ]"
timeout 20 "$PY" scripts/bench-cooling.py --reps 2 >"$tmp/out.txt" 2>"$tmp/err.txt"
rc=$?
check "bench-cooling.py --reps 2: exit 2 (got $rc), one line naming its environment" \
    "[ $rc = 2 ] && [ \$(wc -l <'$tmp/err.txt') = 1 ] && grep -q 'environment variables, NS' '$tmp/err.txt' &&
     [ ! -e '$tmp/out' ]"

timeout 20 "$PY" scripts/bench-pile.py --help >"$tmp/out.txt" 2>"$tmp/err.txt"
rc=$?
check "bench-pile.py --help: exit 0 (got $rc), its description whole" \
    "[ $rc = 0 ] && tr '\n' ' ' <'$tmp/out.txt' | grep -q 'e = 0.5 against *e = 1, on 1 and 2 threads'"

test_end bench_args
