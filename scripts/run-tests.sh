#!/usr/bin/env bash
# Runs test binaries and shell tests from the repository root, each under a time limit, and
# prints one closing line "N passed, N failed, N skipped". A test that exits 77 (the automake
# convention) was skipped: it says why on its own output and is counted as a skip, never as a
# pass. A test that runs past its limit is a hang: "TIMEOUT name after N s" and a failure.
# With --valgrind, each binary runs under memcheck and any leak or error fails.
# Limits (seconds): NBEP_TEST_TIMEOUT (default 300) natively, NBEP_VALGRIND_TIMEOUT (default
# 1800) under valgrind; the slowest test took about a tenth of either on the 2-core CI machine
# until 2026-11-29, when a guest whose thread wake-ups cost 0.3 to 0.5 ms took test_granular past
# 900 s under valgrind (its threaded runs are cut down under valgrind since, and the limit doubled
# for such machines).
set -u
valgrind=0
if [ "${1:-}" = "--valgrind" ]; then valgrind=1; shift; fi
limit=${NBEP_TEST_TIMEOUT:-300}
[ "$valgrind" = 1 ] && limit=${NBEP_VALGRIND_TIMEOUT:-1800}
mkdir -p build/tests/tmp
passed=0 failed=0 skipped=0 failures=() skips=()
for t in "$@"; do
    name=$(basename "$t")
    label=$name
    if [ "$valgrind" = 1 ]; then
        # Smaller problem sizes under valgrind (tests read NBEP_TEST_SCALE); OpenMP's pool is
        # torn down at exit so no "still reachable" is reported by libgomp.
        label="valgrind $name"
        log=build/tests/tmp/$name.valgrind.log
        NBEP_TEST_SCALE=small OMP_WAIT_POLICY=passive timeout -k 10 "$limit" \
            valgrind --quiet --error-exitcode=99 --leak-check=full --errors-for-leak-kinds=definite,indirect \
            --suppressions=tests/valgrind.supp "$t" >"$log" 2>&1
        rc=$?
    else
        case "$t" in *.sh) runner=(bash) ;; *) runner=() ;; esac
        # -k: a test that ignores SIGTERM is killed 10 s later
        timeout -k 10 "$limit" "${runner[@]}" "$t"
        rc=$?
    fi
    if [ "$rc" = 0 ]; then
        passed=$((passed + 1)); [ "$valgrind" = 1 ] && echo "ok   $label"
    elif [ "$rc" = 77 ]; then
        skipped=$((skipped + 1)); skips+=("$label"); echo "SKIP $label"
    else
        failed=$((failed + 1)); failures+=("$label")
        if [ "$rc" = 124 ] || [ "$rc" = 137 ]; then
            echo "TIMEOUT $label after $limit s (a hang is a failure)"
        else
            echo "FAIL $label (exit $rc)"
        fi
        [ "$valgrind" = 1 ] && tail -n 30 "$log"
    fi
done
[ "$failed" -eq 0 ] || printf 'failed: %s\n' "${failures[*]}"
[ "$skipped" -eq 0 ] || printf 'skipped: %s\n' "${skips[*]}"
echo "$passed passed, $failed failed, $skipped skipped"
[ "$failed" -eq 0 ]
