#!/usr/bin/env bash
# Runs test binaries from the repository root and prints one closing line
# "N passed, N failed". With --valgrind, each runs under memcheck and any leak or error fails.
set -u
valgrind=0
if [ "${1:-}" = "--valgrind" ]; then valgrind=1; shift; fi
mkdir -p build/tests/tmp
passed=0 failed=0 failures=()
for t in "$@"; do
    name=$(basename "$t")
    if [ "$valgrind" = 1 ]; then
        # Smaller problem sizes under valgrind (tests read NBEP_TEST_SCALE); OpenMP's pool is
        # torn down at exit so no "still reachable" is reported by libgomp.
        log=build/tests/tmp/$name.valgrind.log
        if NBEP_TEST_SCALE=small OMP_WAIT_POLICY=passive \
            valgrind --quiet --error-exitcode=99 --leak-check=full --errors-for-leak-kinds=definite,indirect \
            --suppressions=tests/valgrind.supp "$t" >"$log" 2>&1; then
            passed=$((passed + 1)); echo "ok   valgrind $name"
        else
            failed=$((failed + 1)); failures+=("valgrind $name"); echo "FAIL valgrind $name"; tail -n 30 "$log"
        fi
    else
        case "$t" in *.sh) runner=(bash) ;; *) runner=() ;; esac
        if "${runner[@]}" "$t"; then
            passed=$((passed + 1))
        else
            failed=$((failed + 1)); failures+=("$name")
        fi
    fi
done
[ "$failed" -eq 0 ] || printf 'failed: %s\n' "${failures[*]}"
echo "$passed passed, $failed failed"
[ "$failed" -eq 0 ]
