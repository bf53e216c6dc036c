#!/usr/bin/env bash
# ThreadSanitizer over the threaded tests (the team loop's apartness audit among them). GCC's libgomp is not instrumented, so TSan cannot
# see OpenMP's own synchronisation; clang with LLVM's libomp and its Archer tool can. Builds
# into build-tsan/ and runs the test binaries with 4 threads (more than this machine's cores,
# to vary interleavings). Exit status 1 when TSan reports anything or a test fails.
set -euo pipefail
cd "$(dirname "$0")/.."
llvm=$(ls -d /usr/lib/llvm-*/ 2>/dev/null | sort -V | tail -n 1)
archer=${llvm}lib/libarcher.so
if ! command -v clang >/dev/null || [ ! -e "$archer" ]; then
    echo "tsan.sh: needs clang and libomp-dev (Archer); run scripts/install-deps.sh" >&2
    exit 2
fi
out=build-tsan
mkdir -p "$out" build/tests/tmp   # the tests write their files there (nbep_test_tmp)
make -s build/build_info.h
cflags="-std=c11 -D_POSIX_C_SOURCE=200809L -O1 -g -fopenmp=libomp -fsanitize=thread
        -ffp-contract=off -Iinclude -Isrc -Itests -Ibuild $(pkg-config --cflags gsl libconfig hdf5 jansson)"
libs="$(pkg-config --libs gsl libconfig hdf5 jansson cmocka) -lm -lpthread -fopenmp=libomp
      -fsanitize=thread -L${llvm}lib -Wl,-rpath,${llvm}lib"
srcs=$(ls src/*.c | grep -v -e '^src/main.c$' -e '^src/sweep.c$')
fail=0
for t in test_sim test_periodic test_barrier test_extremes test_order test_granular \
    test_evloop_apart test_team_faults; do
    [ -e tests/$t.c ] || continue
    # test_evloop_apart and test_team_faults compile their own copy of the cells engine (with
    # their hooks)
    these=$srcs
    grep -q '^#include "../src/evloop.c"' tests/$t.c &&
        these=$(echo "$srcs" | grep -v -e '^src/evloop.c$' -e '^src/evloop_team.c$')
    # shellcheck disable=SC2086
    clang $cflags $these tests/$t.c -o "$out/$t" $libs
    log=$out/$t.log
    if OMP_TOOL_LIBRARIES=$archer TSAN_OPTIONS="ignore_noninstrumented_modules=1 exitcode=66" \
        OMP_NUM_THREADS=4 NBEP_TEST_SCALE=small "$out/$t" >"$log" 2>&1 &&
        ! grep -q "ThreadSanitizer" "$log"; then
        echo "ok   tsan $t"
    else
        echo "FAIL tsan $t (see $log)"; grep -m5 "SUMMARY" "$log" || tail -n 5 "$log"; fail=1
    fi
done
exit $fail
