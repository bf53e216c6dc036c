#!/usr/bin/env bash
# scripts/optimistic-model.py, the model of an optimistic loop over slabs (README, Threads on
# dense scenes), on traces made by hand whose figures follow from its rules: slabs with
# nothing in common run side by side (2 slabs: 2 times one thread); an event that depends on
# the other slab's event of the same window waits for it, rolled back (a chain across the
# slabs: 1 time, half the events handled again); a dependence on an earlier window costs
# nothing (the barrier settled it); the barrier's and the undo's costs counted as stated; with
# --expiries wait, an expiry whose footprint reaches the other slab waits for it, and with
# --expiries meet ends the window, alone between two (every K-th of them: --meet-every). Then
# the trace bench_parallelism writes (NBEP_PAR_TRACE) of a small fluid: a record for each
# event it counts, each depending on earlier events only. Exit status 1 when a check fails.
. "$(dirname "$0")/lib.sh"
test_tmp optimistic_model
# trace NAME 'time place [dep,dep [reach-up kind]];...': a trace file of the records given
# (no dependences: -; reach down 0; reach up and kind 0 unless given)
trace() {
    "$PY" - "$tmp/$1" "$2" <<'EOF'
import struct, sys
with open(sys.argv[1], "wb") as f:
    for rec in sys.argv[2].split(";"):
        parts = rec.split() + ["-", "0", "0"][len(rec.split()) - 2:]
        deps = [int(d) for d in parts[2].split(",")] if parts[2] != "-" else []
        f.write(struct.pack("<ddddII", float(parts[0]), float(parts[1]), 0.0, float(parts[3]),
                            int(parts[4]), len(deps)))
        f.write(struct.pack(f"<{len(deps)}I", *deps))
EOF
}
# row FILE SLABS W: the table's row for those slabs and window
row() { grep -E "^\| $2 \| $3 \|" "$1"; }
model() { "$PY" scripts/optimistic-model.py "$@"; }

trace apart '0.125 0.25;0.125 0.75;0.25 0.25;0.25 0.75;0.375 0.25;0.375 0.75'
model "$tmp/apart" --slabs 1,2 --windows 10 --barrier 0 >"$tmp/apart.txt" 2>&1
check "two slabs with nothing in common: 2 times one thread, nothing handled again" \
    "row '$tmp/apart.txt' 2 10 | grep -qF '| 0.0 % | 2.00 |' &&
     row '$tmp/apart.txt' 1 10 | grep -qF '| 0.0 % | 1.00 |'"
trace chain '0.125 0.25;0.25 0.75 0;0.375 0.25 1;0.5 0.75 2'
model "$tmp/chain" --slabs 2 --windows 10 --barrier 0 --undo 0 >"$tmp/chain.txt" 2>&1
check "a chain across the slabs: 1 time one thread, each event after the first handled again" \
    "row '$tmp/chain.txt' 2 10 | grep -qF '| 75.0 % | 1.00 |'"
model "$tmp/chain" --slabs 2 --windows 10 --barrier 0 --undo 1 >"$tmp/undo.txt" 2>&1
# each late event waits for its cause and undoes what its slab did since: 1, 2, then 3 events
check "the chain with an undo as dear as an event: 4 events in 10 (0.40)" \
    "row '$tmp/undo.txt' 2 10 | grep -qF '| 0.40 |'"
model "$tmp/chain" --slabs 2 --windows 0.125 --barrier 0 --undo 1 >"$tmp/windows.txt" 2>&1
check "the chain one event a window: what the barrier settled costs nothing (1 time one thread)" \
    "row '$tmp/windows.txt' 2 0.125 | grep -qF '| 0.0 % | 1.00 |'"
model "$tmp/apart" --slabs 2 --windows 10 --barrier 1 >"$tmp/barrier.txt" 2>&1
check "a barrier as dear as an event: 6 events in 4 (1.50)" \
    "row '$tmp/barrier.txt' 2 10 | grep -qF '| 1.50 |'"
# an expiry of slab 0 after two events of slab 1, then two more of slab 0: ahead, 6 events in 3
# (2.00); waiting for slab 1 when its footprint reaches there, in 5 (1.20); not when it does not
trace expiry '0.125 0.75;0.1875 0.75;0.25 0.25 - 0.3 1;0.375 0.75;0.5 0.25;0.625 0.25'
trace inside '0.125 0.75;0.1875 0.75;0.25 0.25 - 0.2 1;0.375 0.75;0.5 0.25;0.625 0.25'
model "$tmp/expiry" --slabs 2 --windows 10 --barrier 0 >"$tmp/ahead.txt" 2>&1
model "$tmp/expiry" --slabs 2 --windows 10 --barrier 0 --expiries wait >"$tmp/wait.txt" 2>&1
model "$tmp/inside" --slabs 2 --windows 10 --barrier 0 --expiries wait >"$tmp/inside.txt" 2>&1
check "an expiry reaching the other slab: 2.00 handled ahead, 1.20 waiting; inside its own, 2.00" \
    "row '$tmp/ahead.txt' 2 10 | grep -qF '| 2.00 |' && row '$tmp/wait.txt' 2 10 | grep -qF '| 1.20 |' &&
     row '$tmp/inside.txt' 2 10 | grep -qF '| 2.00 |' && grep -q '(1 list expiries, wait)' '$tmp/wait.txt'"
# --expiries meet (the scheduled loop's slabs): the expiry reaching across ends the window,
# alone between two: 2 events, it, then 2 (1.20); with a barrier as dear as an event, 7 (0.86);
# inside its own slab it does not (2.00); a second one reaching across meets too (6 in 6:
# 1.00), but with --meet-every 2 goes ahead (1.20)
trace expiry2 '0.125 0.75;0.1875 0.75;0.25 0.25 - 0.3 1;0.375 0.75;0.5 0.25 - 0.3 1;0.625 0.25'
model "$tmp/expiry" --slabs 2 --windows 10 --barrier 0 --expiries meet >"$tmp/meet.txt" 2>&1
model "$tmp/expiry" --slabs 2 --windows 10 --barrier 1 --expiries meet >"$tmp/meetb.txt" 2>&1
model "$tmp/inside" --slabs 2 --windows 10 --barrier 0 --expiries meet >"$tmp/meeti.txt" 2>&1
model "$tmp/expiry2" --slabs 2 --windows 10 --barrier 0 --expiries meet >"$tmp/meet2.txt" 2>&1
model "$tmp/expiry2" --slabs 2 --windows 10 --barrier 0 --expiries meet --meet-every 2 \
    >"$tmp/meet2e.txt" 2>&1
# after a meeting, nothing before it is read too soon: slab 0's event, then its expiry reaching
# across (met), then two of slab 1's reading both: 1 + the meeting's 1, then 2 (4 in 4: 1.00,
# nothing handled again; were the meeting not a window's end, slab 1's first would be
# handled again: 0.75)
trace after '0.1 0.25;0.2 0.25 - 0.3 1;0.3 0.75 0,1;0.4 0.75 1'
model "$tmp/after" --slabs 2 --windows 10 --barrier 0 --expiries meet >"$tmp/after.txt" 2>&1
check "an expiry reaching the other slab at a meeting: 1.20, 0.86 with a barrier of 1; inside its own, 2.00; two meeting 1.00, every second one 1.20; what came before a meeting read freely after it (1.00)" \
    "row '$tmp/meet.txt' 2 10 | grep -qF '| 1.20 |' && row '$tmp/meetb.txt' 2 10 | grep -qF '| 0.86 |' &&
     row '$tmp/meeti.txt' 2 10 | grep -qF '| 2.00 |' && row '$tmp/meet2.txt' 2 10 | grep -qF '| 1.00 |' &&
     row '$tmp/meet2e.txt' 2 10 | grep -qF '| 1.20 |' &&
     row '$tmp/after.txt' 2 10 | grep -qF '| 0.0 % | 1.00 |'"

# bench_parallelism's trace of a small periodic fluid, cells mode, one thread
bench=build/bench/bench_parallelism
cat >"$tmp/fluid.deck" <<'EOF'
run: { algorithm = "predictive"; neighbors = "cells"; steps = 10; dt = 0.05; threads = 1; seed = 3; };
box: { min = [0.0, 0.0, 0.0]; max = [8.0, 8.0, 8.0]; periodic = [true, true, true]; };
spheres = ( { count = 216; radius = 0.5; mass = 1.0; place = "lattice"; speed = 1.7320508075688772; } );
output: { file = "fluid.h5"; every = 10; };
EOF
NBEP_PAR_TRACE="$tmp/fluid.bin" "$bench" run "$tmp/fluid.deck" -o "$tmp/fluid.h5" -t 1 --quiet \
    >"$tmp/bench.out" 2>"$tmp/bench.err"
rc=$?
events=$(sed -n 's/^bench_parallelism: \([0-9]*\) events from .*/\1/p' "$tmp/bench.err")
"$PY" - "$tmp/fluid.bin" >"$tmp/read.txt" 2>&1 <<'EOF'
import struct, sys
data = open(sys.argv[1], "rb").read()
off, n, bad, t_last = 0, 0, 0, -1.0
kinds = set()
while off < len(data):
    t, x, lo, hi, kind, k = struct.unpack_from("<ddddII", data, off)
    off += 40
    deps = struct.unpack_from(f"<{k}I", data, off)
    off += 4 * k
    bad += (t < t_last or not 0.0 <= x <= 1.0 or any(d >= n for d in deps) or
            len(set(deps)) != k or not -0.5 <= lo <= 0.0 <= hi <= 0.5 or kind > 2)
    kinds.add(kind)
    t_last, n = t, n + 1
print(n, bad, off == len(data), sorted(kinds))
EOF
check "bench_parallelism's trace: exit 0 (got $rc), a record for each of its $events events, in time order, each depending on distinct earlier ones, its footprint within half the box, all three kinds" \
    "[ $rc = 0 ] && [ -n '$events' ] && [ '$events' -gt 100 ] &&
     grep -qxF '$events 0 True [0, 1, 2]' '$tmp/read.txt'"
NBEP_PAR_TRACE="$tmp/none/fluid.bin" "$bench" run "$tmp/fluid.deck" -o "$tmp/fluid2.h5" -t 1 \
    --quiet >/dev/null 2>"$tmp/none.err"
rc=$?
check "a trace that cannot be written: exit 2 (got $rc), the one line naming it" \
    "[ $rc = 2 ] && grep -qx 'bench_parallelism: cannot write the trace $tmp/none/fluid.bin' '$tmp/none.err'"
model "$tmp/fluid.bin" --slabs 2 --windows 0.01 >"$tmp/fluid.txt" 2>&1
check "the model reads it: a row for 2 slabs" "row '$tmp/fluid.txt' 2 0.01 | grep -qE '\| [0-9.]+ \|$'"

# bench_windows (what ends the scheduled loop's windows on slabs) on the same fluid, 2 slabs on
# 2 threads: one line, with meetings, no more moves than meetings nor meetings than windows,
# and the frames bin/nbep writes
NBEP_SCHEDULED=1 NBEP_SLABS=2 build/bench/bench_windows run "$tmp/fluid.deck" \
    -o "$tmp/windows.h5" -t 2 --quiet >/dev/null 2>"$tmp/windows.err"
rc=$?
bin/nbep run "$tmp/fluid.deck" -o "$tmp/plain.h5" -t 1 --quiet >/dev/null 2>&1
read -r wins meets moves <<<"$(sed -n 's/^bench_windows: 2 slabs: \([0-9]*\) windows, \([0-9]*\) meetings, \([0-9]*\) of them.*/\1 \2 \3/p' "$tmp/windows.err")"
check "bench_windows, 2 slabs on 2 threads: exit 0 (got $rc), one line: ${wins:-?} windows, ${meets:-?} meetings, ${moves:-?} moving; the plain run's frames" \
    "[ $rc = 0 ] && [ \$(grep -c '^bench_windows: ' '$tmp/windows.err') = 1 ] &&
     [ '${meets:-0}' -gt 0 ] && [ '${moves:-0}' -le '${meets:-0}' ] && [ '${meets:-0}' -le '${wins:-0}' ] &&
     h5diff -q '$tmp/plain.h5' '$tmp/windows.h5' /frames"
# ... and its counts of what was undone: no more copies late than messages acted on, and no more
# undone by the meetings' cuts than undone in all
read -r applied late undone cut <<<"$(sed -n 's/.* \([0-9]*\) messages acted on (\([0-9]*\) of them late.* \([0-9]*\) undone, .* cuts undid \([0-9]*\) in .*/\1 \2 \3 \4/p' "$tmp/windows.err")"
check "bench_windows: ${late:-?} of ${applied:-?} messages late, ${cut:-?} of ${undone:-?} undone by the cuts" \
    "[ -n '$applied' ] && [ '${late:-0}' -le '${applied:-0}' ] && [ '${cut:-0}' -le '${undone:-0}' ]"

# bench_versions (the scheme's bookkeeping on one thread) on a fluid long across x: with
# NBEP_VER_VERIFY every list is read through, and no member of another slab may sit in a list
# that the side's reach skips, nor be read from another slab with no record kept; no read
# comes too soon in the serial order; the bookkeeping (whole versions on 2 slabs, lean ones
# written past the caches on 3) changes nothing the run writes
versions=build/bench/bench_versions
cat >"$tmp/long.deck" <<'EOF'
run: { algorithm = "predictive"; neighbors = "cells"; steps = 10; dt = 0.05; threads = 1; seed = 5; };
box: { min = [0.0, 0.0, 0.0]; max = [24.0, 8.0, 8.0]; periodic = [true, true, true]; };
spheres = ( { count = 768; radius = 0.5; mass = 1.0; place = "lattice"; speed = 1.7320508075688772; } );
output: { file = "long.h5"; every = 10; };
EOF
"$versions" run "$tmp/long.deck" -o "$tmp/long0.h5" -t 1 --quiet --summary "$tmp/long0.json" \
    2>"$tmp/long0.err"
rc0=$?
for s in 2 3; do
    # lean versions, streamed, on 3 slabs (lean_save reads the cells callbacks' context)
    NBEP_VER_LEAN=$([ $s = 3 ] && echo 2 || echo 0) \
        NBEP_VER_VERIFY=1 NBEP_VER_SLABS=$s NBEP_VER_WINDOW=0.02 "$versions" run "$tmp/long.deck" \
        -o "$tmp/long$s.h5" -t 1 --quiet --summary "$tmp/long$s.json" 2>"$tmp/long$s.err"
    rc=$?
    tally=$(cat "$tmp/long$s.err")
    num() { echo "$tally" | sed -n "s/.* \([0-9][0-9]*\) $1.*/\1/p"; }
    check "bench_versions, $s slabs: exit 0 (got $rc); lists near a side read, fewer than the versions; notes and messages; none skipped wrongly, none too soon: $tally" \
        "[ $rc = 0 ] && [ $rc0 = 0 ] && [ '$(num 'lists near')' -gt 0 ] &&
         [ '$(num 'lists near')' -lt '$(num versions)' ] && [ '$(num notes)' -gt 0 ] &&
         [ '$(num messages)' -gt 0 ] && echo '$tally' | grep -q ', 0 reads too soon, 0 reads of another slab in lists skipped\$'"
    check "bench_versions, $s slabs: the run's collisions and energy those of the run without" \
        "[ \"\$(grep -o '\"collisions\": [0-9]*\|\"energy_final\": [^,]*' '$tmp/long$s.json')\" = \
           \"\$(grep -o '\"collisions\": [0-9]*\|\"energy_final\": [^,]*' '$tmp/long0.json')\" ] &&
         grep -q '\"collisions\": [1-9]' '$tmp/long0.json'"
done
# the same with the records and notes in src/versions.c (NBEP_VER_MODULE): puts and reads on
# 2 slabs, none sent back in the serial order but by a read at the put's own time (a lattice's
# ties: every list expires at once), and with pools of 64 versions the windows that fill one
# end early; the messages through src/mail.c, every window's meeting finding its work done; the
# events logged in src/undo.c; the run unchanged
for room in 0 64; do
    NBEP_VER_MODULE=1 NBEP_VER_ROOM=$room NBEP_VER_VERIFY=1 NBEP_VER_SLABS=2 NBEP_VER_WINDOW=0.02 \
        "$versions" run "$tmp/long.deck" -o "$tmp/longm$room.h5" -t 1 --quiet \
        --summary "$tmp/longm$room.json" 2>"$tmp/longm$room.err"
    rc=$?
    tally=$(cat "$tmp/longm$room.err")
    num() { echo "$tally" | sed -n "s/.* \([0-9][0-9]*\) $1.*/\1/p"; }
    full=$([ $room = 0 ] && echo "= 0" || echo "-gt 0")
    check "bench_versions on versions.c, pools of ${room/#0/the default} versions: exit 0 (got $rc); puts, a read for each note, none sent back but at a tie, pools full $full; messages through mail.c, all taken but the last window's, every meeting quiet: $tally" \
        "[ $rc = 0 ] && [ '$(num puts)' -gt 0 ] && [ '$(num reads,)' = '$(num notes)' ] &&
         [ '$(num 'pools full')' $full ] && [ '$(num 'messages taken')' -gt 0 ] &&
         [ '$(num 'messages taken')' -le '$(num 'messages,')' ] &&
         echo '$tally' | grep -q ' boxes full, 0 meetings not quiet' &&
         echo '$tally' | grep -q ', 0 reads too soon, 0 reads of another slab in lists skipped;' &&
         echo '$tally' | grep -q ', 0 sent back with no read at their time; undo.c: [1-9][0-9]* events logged in the last window\$'"
    check "bench_versions on versions.c, pools of ${room/#0/the default}: the run's collisions and energy those of the run without" \
        "[ \"\$(grep -o '\"collisions\": [0-9]*\|\"energy_final\": [^,]*' '$tmp/longm$room.json')\" = \
           \"\$(grep -o '\"collisions\": [0-9]*\|\"energy_final\": [^,]*' '$tmp/long0.json')\" ]"
done
windows() { sed -n 's/.* \([0-9][0-9]*\) windows.*/\1/p' "$1"; }
check "bench_versions on versions.c: pools of 64 end windows early ($(windows "$tmp/longm64.err") windows against $(windows "$tmp/longm0.err"))" \
    "[ '$(windows "$tmp/longm64.err")' -gt '$(windows "$tmp/longm0.err")' ]"
NBEP_VER_SLABS=65 "$versions" run "$tmp/long.deck" -o "$tmp/long9.h5" -t 1 --quiet 2>"$tmp/bad.err"
rc=$?
check "bench_versions, 65 slabs: exit 2 (got $rc), one line" \
    "[ $rc = 2 ] && [ \$(wc -l <'$tmp/bad.err') = 1 ] && grep -q 'NBEP_VER_SLABS from 0 to 64' '$tmp/bad.err'"
test_end test_optimistic_model
