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
libs="$(pkg-config --libs gsl libconfig hdf5 jansson cmocka) -lhdf5_hl -lm -lpthread -fopenmp=libomp
      -fsanitize=thread -L${llvm}lib -Wl,-rpath,${llvm}lib"
srcs=$(ls src/*.c | grep -v -e '^src/main.c$' -e '^src/sweep.c$')
fail=0
for t in test_sim test_periodic test_barrier test_extremes test_order test_granular test_versions test_mail test_warp \
    test_evloop_apart test_team_faults test_detect_stop test_sched_slabs; do
    [ -e tests/$t.c ] || continue
    # test_evloop_apart and test_team_faults compile their own copy of the cells engine (with
    # their hooks), test_detect_stop its own of the naive and seminaive algorithms, test_warp
    # its own of the scheduler, test_sched_slabs its own of the engine's loop through it (the
    # slabs on 2 and 4 threads)
    these=$srcs
    grep -q '^#include "../src/evloop.c"' tests/$t.c &&
        these=$(echo "$srcs" | grep -v -e '^src/evloop.c$' -e '^src/evloop_team.c$')
    grep -q '^#include "../src/algo_detect.c"' tests/$t.c &&
        these=$(echo "$srcs" | grep -v -e '^src/algo_detect.c$')
    grep -q '^#include "../src/warp.c"' tests/$t.c &&
        these=$(echo "$these" | grep -v -e '^src/warp.c$')
    grep -q '^#include "../src/evloop_warp.c"' tests/$t.c &&
        these=$(echo "$these" | grep -v -e '^src/evloop_warp.c$')
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
# the binary itself, stopped by SIGTERM within a step of minutes (dt = 10000) on 4 threads:
# the all-pairs and grid modes' crews (thread 0 looks at the signal and the crew reads what it
# found past a barrier) and cells mode's team abandon the step, and so does naive's pass over
# the pairs of 16384 spheres (seconds a step here; every thread looks at the signal and all
# read past a barrier whether one found it), and cells mode's first rebuild, signalled as soon
# as frame 0 is in the file (the fluid at 256000 spheres, whose rebuild takes seconds under
# TSan: every thread looks at the signal between chunks of its predictions, and all read past
# a barrier whether one found it; on a machine fast enough to be past it, the step's events,
# minutes at dt = 1000, abandon it); TSan must see no race on the way out, and the run must
# end as terminated (143)
# shellcheck disable=SC2086
clang $cflags $(ls src/*.c) -o "$out/nbep" $libs
for mode in all grid cells naive rebuild; do
    log=$out/nbep-abandon-$mode.log
    rm -f "$out/abandon-$mode.h5"
    deck=inputs/paper-box.deck wait_s=2
    if [ $mode = naive ]; then
        what=(-a naive --set 'spheres.[0].count=16384')
    elif [ $mode = rebuild ]; then
        deck=inputs/hard-sphere-fluid.deck wait_s=0
        what=(--set run.dt=1000 --set 'spheres.[0].count=256000'
              --set 'box.max=[76.4491118418, 76.4491118418, 76.4491118418]')
    else
        what=(--set run.dt=10000 --set 'spheres.[0].count=1000'
              --set 'physics.gravity=[0.0, 0.0, 0.0]' --set "run.neighbors=\"$mode\"")
    fi
    OMP_TOOL_LIBRARIES=$archer TSAN_OPTIONS="ignore_noninstrumented_modules=1 exitcode=66" \
        "$out/nbep" run "$deck" --quiet -t 4 -n 3 "${what[@]}" \
        -o "$out/abandon-$mode.h5" >"$log" 2>&1 &
    pid=$!
    for _ in $(seq 600); do [ -s "$out/abandon-$mode.h5" ] && break; sleep 0.1; done
    # frame 0 in the file: the steps (the rebuild first) come next
    for _ in $(seq 600); do
        "$out/nbep" info "$out/abandon-$mode.h5" 2>/dev/null | grep -q '^frames: *[1-9]' && break
        sleep 0.1
    done
    sleep $wait_s
    kill -TERM $pid
    stopped=0
    for _ in $(seq 600); do
        if ! kill -0 $pid 2>/dev/null; then stopped=1; break; fi
        sleep 0.1
    done
    [ $stopped = 1 ] || kill -KILL $pid
    rc=0
    wait $pid || rc=$?
    if [ $rc = 143 ] && ! grep -q "ThreadSanitizer" "$log" && grep -q 'which is abandoned' "$log"; then
        echo "ok   tsan nbep: SIGTERM abandons a step in $mode mode"
    else
        echo "FAIL tsan nbep: $mode mode, exit $rc (see $log)"; grep -m5 "SUMMARY" "$log" || tail -n 5 "$log"; fail=1
    fi
done
# a pile settling on 4 threads in cells mode, a frame every 10 steps: the spheres the settle
# phase holds record their supports on each thread before thread 0 writes the frame's lasting
# state, which reads them all (until 2026-12-02 no barrier stood between: TSan saw the race,
# and on 2 threads a settled pile's /checkpoint/contacts said a support had changed where one
# thread's said not; about 150 s under TSan here)
log=$out/nbep-settle.log
rm -f "$out/settle.h5"
rc=0
OMP_TOOL_LIBRARIES=$archer TSAN_OPTIONS="ignore_noninstrumented_modules=1 exitcode=66" \
    timeout 900 "$out/nbep" run inputs/pile.deck --quiet -t 4 -n 1000 \
    --set 'spheres.[0].count=100' --set 'box.max=[0.25, 0.25, 1.2]' \
    --set physics.restitution=0.3 --set output.every=10 -o "$out/settle.h5" >"$log" 2>&1 || rc=$?
if [ $rc = 0 ] && ! grep -q "ThreadSanitizer" "$log"; then
    echo "ok   tsan nbep: a settling pile's frames on 4 threads"
else
    echo "FAIL tsan nbep: a settling pile, exit $rc (see $log)"; grep -m5 "SUMMARY" "$log" || tail -n 5 "$log"; fail=1
fi
exit $fail
