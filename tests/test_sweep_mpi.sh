#!/usr/bin/env bash
# `nbep sweep` under `mpirun -np 2`: both ranks run runs (the rank column of summary.csv), rank
# 0's summary has every run, each run's file exists, and the same command again reuses them
# all. A build without MPI (make MPI=0) must refuse to run as one of several MPI processes
# (each would run the whole sweep) instead. Skipped only when mpirun is not installed.
. "$(dirname "$0")/lib.sh"
# Under `make asan` the ranks would report Open MPI's own allocations, kept until exit (many
# from components it loads and unloads, which LeakSanitizer cannot even name); nbep's sweep
# code is leak-checked by test_sweep, which runs it without MPI.
export ASAN_OPTIONS="${ASAN_OPTIONS:+$ASAN_OPTIONS:}detect_leaks=0"
if ! command -v mpirun >/dev/null 2>&1; then
    echo "skipped: mpirun not found"
    exit 77 # scripts/run-tests.sh counts it a skip, not a pass
fi
test_tmp sweep_mpi
# rank_pid DECK RANK: the pid of that rank of the sweep of DECK (its environment says which),
# nothing while it has not started
rank_pid() {
    local p
    for p in $(pgrep -f "nbep sweep $1"); do
        tr '\0' '\n' <"/proc/$p/environ" 2>/dev/null | grep -qx "OMPI_COMM_WORLD_RANK=$2" &&
            echo "$p" && return
    done
}

cat >"$tmp/mpi.deck" <<'EOF'
# 2 replicas x 2 restitutions x 2 algorithms = 8 short runs of 16 spheres
run: { algorithm = "predictive"; steps = 50; dt = 1.0e-3; threads = 1; seed = 3; };
physics: { gravity = [0.0, 0.0, -9.81]; restitution = 1.0; };
box: { min = [0.0, 0.0, 0.0]; max = [1.0, 1.0, 1.0]; };
spheres = ( { count = 16; radius = 0.05; mass = 1.0; place = "random"; speed = 1.0; } );
output: { file = "mpi.h5"; every = 10; };
sweep: { replicas = 2;
  vary = ( { key = "physics.restitution"; values = [1.0, 0.9]; },
           { key = "run.algorithm"; values = ["naive", "predictive"]; } ); };
EOF

# Open MPI refuses to run as root without these two; --oversubscribe allows 2 ranks on a
# machine with fewer free cores. Containers often forbid the cross-memory attach that Open
# MPI's shared-memory transport uses for large messages: copy through the shared segment.
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
export OMPI_MCA_btl_vader_single_copy_mechanism=none
# one thread per rank: two ranks on two cores
export OMP_NUM_THREADS=1
sweep() {
    timeout 300 mpirun -np 2 --oversubscribe bin/nbep sweep "$tmp/mpi.deck" -o "$tmp/mpi.h5" \
        --summary "$tmp/$1.json" 2>"$tmp/$1.stderr"
}

if ! bin/nbep --version | grep -q 'MPI=1'; then
    sweep nompi
    rc=$?
    check "a build without MPI refuses to run under mpirun -np 2 (exit $rc)" "[ $rc -ne 0 ]"
    check "and says why" "grep -q 'built without MPI' '$tmp/nompi.stderr'"
    [ $fail = 0 ] && echo "sweep_mpi: all passed (MPI=0 build)"
    exit $fail
fi

sweep first
rc=$?
csv=$tmp/mpi.sweep/summary.csv
if [ $rc -ne 0 ] || [ ! -s "$csv" ]; then
    echo "FAIL mpirun -np 2 nbep sweep exited $rc; its stderr:"
    cat "$tmp/first.stderr"
    exit 1
fi
check "the sweep exits 0" "[ $rc = 0 ]"
check "summary.csv has a header and 8 runs" "[ \$(wc -l <'$csv') = 9 ]"
# columns: run,replica,seed,rank,physics.restitution,run.algorithm,status,...
check "every run is ok" "[ \$(cut -d, -f7 '$csv' | grep -c '^ok$') = 8 ]"
check "rank 0 ran runs" "cut -d, -f4 '$csv' | grep -qx 0"
check "rank 1 ran runs" "cut -d, -f4 '$csv' | grep -qx 1"
# rounds of 2 in alternating direction: runs 0,3,4,7 on rank 0 and 1,2,5,6 on rank 1
owners=$(tail -n +2 "$csv" | cut -d, -f1,4 | tr '\n' ' ')
check "runs are dealt in alternating rounds ($owners)" \
    "[ '$owners' = '0,0 1,1 2,1 3,0 4,0 5,1 6,1 7,0 ' ]"
check "each run wrote its own file" "[ \$(ls '$tmp/mpi.sweep' | grep -c '^run-000[0-7].h5$') = 8 ]"
check "summary.h5 exists" "[ -s '$tmp/mpi.sweep/summary.h5' ]"
check "the sweep's JSON says 8 runs on 2 ranks" \
    "grep -q '\"runs\": 8, \"ok\": 8, .*\"ranks\": 2' '$tmp/first.json'"
check "per-run progress lines name both ranks" \
    "grep -q 'rank 0: run' '$tmp/first.stderr' && grep -q 'rank 1: run' '$tmp/first.stderr'"

sweep again
rc=$?
check "the same command again exits 0 (exit $rc)" "[ $rc = 0 ]"
check "and reuses all 8 runs" "grep -q '\"reused\": 8' '$tmp/again.json'"

# ---- a SIGTERM that reaches one rank alone stops the new runs of both ----------------------
# 8 runs of a few seconds each (4 a rank); rank 1 alone gets SIGTERM during its first run.
# Rank 0 finishes the run it is in and starts no other (it ran all four before: the signal's
# rank waited for it, asleep); both exit 143, and the table has at most the two first runs
# done and every other run not_run.
mkdir -p "$tmp/one"
sed -e 's/steps = 50;/steps = 150000;/' -e 's/count = 16;/count = 4;/' "$tmp/mpi.deck" >"$tmp/one/one.deck"
timeout 300 mpirun -np 2 --oversubscribe bin/nbep sweep "$tmp/one/one.deck" -o "$tmp/one/one.h5" \
    --summary "$tmp/one/one.json" 2>"$tmp/one/stderr" &
pid=$!
rank1=""
for _ in $(seq 200); do
    rank1=$(rank_pid "$tmp/one/one.deck" 1)
    [ -n "$rank1" ] && [ -e "$tmp/one/one.sweep/run-0000.h5" ] &&
        [ -e "$tmp/one/one.sweep/run-0001.h5" ] && break
    sleep 0.05
done
sleep 0.3
[ -n "$rank1" ] && kill -TERM "$rank1"
wait $pid
rc=$?
csv1=$tmp/one/one.sweep/summary.csv
done_runs=$(tail -n +2 "$csv1" 2>/dev/null | cut -d, -f7 | grep -cE '^(ok|interrupted)$')
not_run=$(tail -n +2 "$csv1" 2>/dev/null | cut -d, -f7 | grep -c '^not_run$')
check "SIGTERM to rank 1 alone: exit 143 (got $rc; rank 1 pid '${rank1}')" "[ $rc = 143 ]"
check "... at most the two first runs ran ($done_runs), the other six not run ($not_run)" \
    "[ $done_runs -le 2 ] && [ $not_run -ge 6 ]"

# ---- a rank done with its runs waits for the others without spinning ----------------------
# Two runs, one a rank: rank 0's of 20 steps, rank 1's of 10^9 (minutes), so that rank 0 waits
# for rank 1 at the end of its share. Open MPI's blocking collectives busy-poll: rank 0 burnt
# a whole core there (89 % of a 3 s window on a quiet 2-core machine; a third with the load at
# 4, as much as the running rank got), where sleeping between polls used 1 to 4 % then. Measured from
# outside, in /proc/PID/stat (utime + stime: the process's threads together), over 3 s that
# start once rank 0's run has ended and end before rank 1's is stopped (SIGTERM: it finishes
# its step, both exit 143, as a stop reaching one rank does): nbep's output stays as it is.
# Two checks. (1) The waiting rank sleeps: it gave up its CPU of its own accord (voluntary
# context switches, /proc/PID/status) at least once per 100 ms of the window on average; a rank
# that polls without sleeping makes none (a sched_yield in its loop counts as involuntary; the
# mutant sweep-wait-spins made 0), one that naps at most 1 ms makes tens to hundreds a second
# (31 to 230 on 2026-11-29's machine, whose naps overran). (2) It used less than half of the window's
# CPU. The CPU check alone was the test until 2026-11-29, at under a quarter of the window and
# of the running rank's CPU; on that day's machine (a Firecracker guest, kernel 6.18) a bare
# loop of 1 ms nanosleeps used 30 % of a core (the idle balancing that each sleep sets off is
# charged to the sleeper), so the waiting rank's 27 to 31 % failed it; a rank that spins uses
# all the core it gets, and fails (1) wherever it runs.
mkdir -p "$tmp/wait"
cat >"$tmp/wait/wait.deck" <<'EOF2'
# rank 0: 20 steps; rank 1: 10^9 steps, stopped by the test (few frames, no per-step stats)
run: { algorithm = "predictive"; steps = 20; dt = 1.0e-3; threads = 1; seed = 3; };
physics: { gravity = [0.0, 0.0, -9.81]; restitution = 1.0; };
box: { min = [0.0, 0.0, 0.0]; max = [1.0, 1.0, 1.0]; };
spheres = ( { count = 4; radius = 0.05; mass = 1.0; place = "random"; speed = 1.0; } );
output: { file = "wait.h5"; every = 1000000; stats = false; };
sweep: { vary = ( { key = "run.steps"; values = [20, 1000000000]; } ); };
EOF2
timeout -k 10 120 mpirun -np 2 --oversubscribe bin/nbep sweep "$tmp/wait/wait.deck" \
    -o "$tmp/wait/wait.h5" 2>"$tmp/wait/stderr" &
pid=$!
r0="" r1=""
for _ in $(seq 400); do
    r0=$(rank_pid "$tmp/wait/wait.deck" 0) r1=$(rank_pid "$tmp/wait/wait.deck" 1)
    [ -n "$r0" ] && [ -n "$r1" ] && grep -q 'rank 0: run 0 .*: ok in' "$tmp/wait/stderr" && break
    sleep 0.05
done
ticks() { awk '{print $14 + $15}' "/proc/$1/stat" 2>/dev/null; }
naps() { awk '/^voluntary_ctxt_switches:/ {print $2}' "/proc/$1/status" 2>/dev/null; }
used="" window="" other="" running="" slept=""
if [ -n "$r0" ] && [ -n "$r1" ]; then
    sleep 0.5 # past the progress line, into the wait
    c0=$(ticks "$r0") d0=$(ticks "$r1") v0=$(naps "$r0") t0=$(date +%s%N)
    sleep 3
    c1=$(ticks "$r0") d1=$(ticks "$r1") v1=$(naps "$r0") t1=$(date +%s%N)
    # rank 1 still in its run: rank 0 waited all through the window
    kill -0 "$r1" 2>/dev/null && ! grep -q 'rank 1: run 1 ' "$tmp/wait/stderr" && running=yes
    hz=$(getconf CLK_TCK)
    # a rank gone before a reading leaves it empty: no figures then (the check fails)
    if [ -n "$c0" ] && [ -n "$c1" ] && [ -n "$d0" ] && [ -n "$d1" ] && [ -n "$v0" ] &&
        [ -n "$v1" ]; then
        used=$(((c1 - c0) * 1000 / hz)) window=$(((t1 - t0) / 1000000)) # milliseconds
        other=$(((d1 - d0) * 1000 / hz)) slept=$((v1 - v0))
    fi
    kill -TERM "$r1"
else
    kill -TERM "$pid"
fi
wait $pid
rc=$?
check "rank 0 waited 3 s for rank 1's run (pids '$r0' '$r1'; rank 1 still running: '$running')" \
    "[ -n '$used' ] && [ '$running' = yes ]"
check "... it slept ${slept:-?} times in ${window:-?} ms: at least once per 100 ms" \
    "[ -n '$slept' ] && [ $((100 * ${slept:-0})) -ge ${window:-1} ]"
check "... ${used:-?} ms CPU in ${window:-?} ms: under half of that (rank 1: ${other:-?} ms)" \
    "[ -n '$used' ] && [ $((2 * ${used:-0})) -lt ${window:-0} ]"
statuses=$(tail -n +2 "$tmp/wait/wait.sweep/summary.csv" 2>/dev/null | cut -d, -f6 | tr '\n' ' ')
check "... then rank 1 stopped by SIGTERM: exit 143 (got $rc), runs ok, interrupted ($statuses)" \
    "[ $rc = 143 ] && [ '$statuses' = 'ok interrupted ' ]"

# ---- a SIGTERM to a rank that waits for the others, done with its runs ----------------------
# 8 runs: rank 0's (0, 3, 4, 7) of 20 steps, rank 1's (1, 2, 5, 6) of 10^6 (seconds each).
# Rank 0 ends its share at once and waits; it alone gets SIGTERM there, during rank 1's first
# run. It tells rank 1, which ends the run it is in and starts no other: exit 143, runs 2, 5
# and 6 (at least two of them) not run. Until 2026-11-29 the waiting rank ignored the signal:
# all 8 runs ran and the sweep exited 0.
mkdir -p "$tmp/late"
# the waiting test's deck with 8 values of run.steps
sed -e 's/values = \[20, 1000000000\]/values = [20, 1000000, 1000000, 20, 20, 1000000, 1000000, 20]/' \
    "$tmp/wait/wait.deck" >"$tmp/late/late.deck"
timeout -k 10 300 mpirun -np 2 --oversubscribe bin/nbep sweep "$tmp/late/late.deck" \
    -o "$tmp/late/late.h5" 2>"$tmp/late/stderr" &
pid=$!
r0=""
for _ in $(seq 400); do
    r0=$(rank_pid "$tmp/late/late.deck" 0)
    [ -n "$r0" ] && grep -q 'rank 0: run 7 .*: ok in' "$tmp/late/stderr" && break
    sleep 0.05
done
sleep 0.3 # into the wait
waited=no
grep -q 'rank 0: run 7 .*: ok in' "$tmp/late/stderr" && ! grep -q 'rank 1: run 2 ' "$tmp/late/stderr" &&
    waited=yes
if [ -n "$r0" ]; then kill -TERM "$r0"; else kill -TERM "$pid"; fi
wait $pid
rc=$?
statuses=$(tail -n +2 "$tmp/late/late.sweep/summary.csv" 2>/dev/null | cut -d, -f6 | tr '\n' ' ')
not_run=$(tail -n +2 "$tmp/late/late.sweep/summary.csv" 2>/dev/null | cut -d, -f6 | grep -c '^not_run$')
check "rank 0 waited, done with its runs, while rank 1 ran its first (pid '$r0': $waited)" \
    "[ '$waited' = yes ]"
check "... SIGTERM to it alone: exit 143 (got $rc), rank 1 started no other run ($statuses)" \
    "[ $rc = 143 ] && [ $not_run -ge 2 ]"

# a rank that cannot see the study's folder (here started in another working directory with a
# relative -o: as a node whose TMPDIR is its own): the sweep stops before any run, exit 2, that
# rank saying why and rank 0 that another rank cannot run it, the folder it made removed
# (until 2026-12-03 each of that rank's runs failed, "cannot create the output file")
mkdir -p "$tmp/r0" "$tmp/r1"
at=$(cd "$tmp" && pwd)
(cd "$tmp/r0" && timeout 120 mpirun --oversubscribe -np 1 "$OLDPWD/bin/nbep" sweep "$at/mpi.deck" \
    -o rel/far.h5 --quiet : -np 1 --wdir "$at/r1" "$OLDPWD/bin/nbep" sweep "$at/mpi.deck" \
    -o rel/far.h5 --quiet) >"$tmp/far.out" 2>&1
rc=$?
check "a rank that cannot see the folder: exit 2 (got $rc), its line, rank 0's: $(grep -m1 'cannot see' "$tmp/far.out" | head -c 300)" \
    "[ $rc = 2 ] && grep -q '^nbep: sweep: rank 1 (on .*) cannot see the study.s folder rel/far.sweep, which rank 0 made (No such file or directory)' '$tmp/far.out' &&
     grep -q '^nbep: sweep: another rank cannot run the study (its line says why); nothing run$' '$tmp/far.out'"
check "... nothing left where rank 0 works: $(ls -A "$tmp/r0")" "[ -z \"\$(ls -A '$tmp/r0')\" ]"

test_end sweep_mpi
