#!/usr/bin/env bash
# Crowded granular scenes that come to rest (issue 9): the rest speed, the cage rule and the
# round-off grazing tolerance (README, granular scenes). Two scenes that ended in a stall or a
# jam, or cost hundreds of thousands of collisions with nothing held, before those rules:
# - a closed V groove: 6 spheres (e = 0.5) dropped into a 45-degree V with an end wall, gravity
#   tilted towards it; before: 110559 collisions in 2000 steps, one sphere held at the end;
#   now 13220, all six held, the last collision at step 1805 (measured 2026-12-02, 4e9fcea);
# - 12 spheres poured into a 0.33 m box: before, the stall check stopped the run at step 949;
#   now it settles, in every neighbour mode (see below).
# "Held" is read off the last frame: a held sphere's velocity is exactly zero. The limits
# below leave room (1.8x to 3x) for the model's counts, and stay far below the old ones; a
# jam stops the run at run.max_reactions = 20000 (the busiest sphere now reacts under 5000
# times in a step), so a regression fails fast instead of hanging. Frames are identical for 1
# and 2 threads. Skipped when /usr/bin/python3 lacks h5py.
. "$(dirname "$0")/lib.sh"
need_py h5py numpy
test_tmp settle
# collisions of a run from its JSON summary
collisions() { sed -n 's/.*"collisions": \([0-9]*\).*/\1/p' "$1"; }
# spheres with exactly zero velocity in the last frame
held() {
    "$PY" -c 'import sys, h5py, numpy as np
v = h5py.File(sys.argv[1], "r")["/frames/velocity"][-1]
print(int((np.abs(v).sum(axis=1) == 0.0).sum()))' "$1"
}

cat >"$tmp/groove.deck" <<'DECK'
run: { algorithm = "predictive"; steps = 3000; dt = 1.0e-3; seed = 1; neighbors = "grid";
       max_reactions = 20000; };
physics: { gravity = [0.0, -1.7, -9.66]; restitution = 0.5; };
planes = ( { normal = [1.0, 0.0, 1.0]; point = [0.0, 0.0, 0.0]; },
           { normal = [-1.0, 0.0, 1.0]; point = [0.0, 0.0, 0.0]; },
           { normal = [0.0, 1.0, 0.0]; point = [0.0, 0.0, 0.0]; } );
spheres = ( { count = 6; radius = 0.05; mass = 1.0; place = "random"; speed = 0.0;
              region: { min = [-0.2, 0.0, 0.3]; max = [0.2, 0.3, 0.6]; }; } );
output: { file = "groove.h5"; every = 100; fields = ["position", "velocity"]; };
DECK

for t in 1 2; do
    timeout -k 5 60 bin/nbep run "$tmp/groove.deck" --quiet -t "$t" -o "$tmp/groove-$t.h5" \
        --summary "$tmp/groove-$t.json" 2>"$tmp/groove-$t.err"
    rc=$?
    check "groove, $t thread(s): runs to exit 0 (got $rc)" "[ $rc -eq 0 ] && [ ! -s '$tmp/groove-$t.err' ]"
done
# (11217 at 2026-11-27; 25817 with the rest of a plane bounce that the TC model made elastic
# taken out, which 30000 let pass once the quartic search's changes moved the trajectories)
c=$(collisions "$tmp/groove-1.json")
check "groove: under 20000 collisions in 3000 steps (got ${c:-none}; before the rest speed: 110559 in 2000)" \
    "[ -n '$c' ] && [ '$c' -lt 20000 ]"
h=$(held "$tmp/groove-1.h5")
check "groove: all 6 spheres held at the end (got ${h:-none})" "[ '${h:-0}' -eq 6 ]"
check "groove: frames identical for 1 and 2 threads" \
    "h5diff -q '$tmp/groove-1.h5' '$tmp/groove-2.h5' /frames /frames >/dev/null 2>&1"

cat >"$tmp/box.deck" <<'DECK'
run: { algorithm = "predictive"; steps = 2000; dt = 1.0e-3; seed = 1; neighbors = "grid";
       max_reactions = 20000; };
physics: { gravity = [0.0, 0.0, -9.81]; restitution = 0.5; };
box: { min = [0.0, 0.0, 0.0]; max = [0.33, 0.33, 0.6]; };
spheres = ( { count = 12; radius = 0.05; mass = 1.0; place = "random"; speed = 0.0; } );
output: { file = "box.h5"; every = 100; fields = ["position", "velocity"]; };
DECK

# Settling (SETTLE_STEPS, src/pred_settle.c) holds the spheres that carry each other: all 12
# (11 in cells mode, where one slides on the floor, frictionless, for good) held, about 47000 to
# 76000 collisions (before settling: 157511 in grid mode, 10 held, 10050 collisions in the last
# 100 steps, for ever); the last collision before step 1200 in grid and all-pairs modes.
for mode in grid cells all; do
    timeout -k 5 90 bin/nbep run "$tmp/box.deck" --quiet -o "$tmp/box-$mode.h5" \
        --set "run.neighbors=\"$mode\"" --summary "$tmp/box-$mode.json" 2>"$tmp/box-$mode.err"
    rc=$?
    check "12 spheres in a 0.33 m box, $mode: run to exit 0 (got $rc; before: the stall check at step 949)" \
        "[ $rc -eq 0 ] && [ ! -s '$tmp/box-$mode.err' ]"
    h=$(held "$tmp/box-$mode.h5")
    check "12 spheres in a 0.33 m box, $mode: at least 11 held at the end (got ${h:-none})" \
        "[ '${h:-0}' -ge 11 ]"
    c=$(collisions "$tmp/box-$mode.json")
    check "12 spheres in a 0.33 m box, $mode: under 120000 collisions (got ${c:-none})" \
        "[ -n '$c' ] && [ '$c' -lt 120000 ]"
done
for mode in grid all; do
    last=$("$PY" -c 'import sys, h5py, numpy as np
c = h5py.File(sys.argv[1], "r")["/stats/collisions"][:]
print(int(np.nonzero(c)[0][-1]) + 1)' "$tmp/box-$mode.h5")
    check "12 spheres in a 0.33 m box, $mode: settled, no collision after step 1500 (last: ${last:-none})" \
        "[ -n '$last' ] && [ '$last' -le 1500 ]"
done
timeout -k 5 90 bin/nbep run "$tmp/box.deck" --quiet -t 2 -o "$tmp/box-grid-2.h5" 2>/dev/null
check "12 spheres in a 0.33 m box, grid: frames identical for 1 and 2 threads (settling included)" \
    "h5diff -q '$tmp/box-grid.h5' '$tmp/box-grid-2.h5' /frames /frames >/dev/null 2>&1"

# A deeper pile: the pile deck's pour with 100 spheres on a floor 0.212 m square (its
# density), seed 2. A held sphere that rests on spheres takes every push as its pile would
# (pred_react.c: the loads through a pile's network are not resolved); asked whether its own
# supports take its weight and the pressing sphere's (as a sphere held on planes is, since
# 2026-12-02), the upper layers woke each other for ever: 4.5 million collisions in the last
# 500 of 2500 steps, where the pile now settles by step 1900 (one sphere slides on).
# (about 25 s alone on this project's machine: its limit is a hang's, five times that, since a
# slow virtual CPU and make check's other tests at once can make it three times as long)
timeout -k 5 300 bin/nbep run inputs/pile.deck --quiet --set 'spheres.[0].count=100' \
    --set 'box.max=[0.212, 0.212, 1.2]' -n 2500 --set run.seed=2 --set output.every=100 \
    -o "$tmp/pile100.h5" 2>"$tmp/pile100.err"
rc=$?
last=$("$PY" -c 'import sys, h5py, numpy as np
c = h5py.File(sys.argv[1], "r")["/stats/collisions"][:]
print(int(np.nonzero(c)[0][-1]) + 1)' "$tmp/pile100.h5" 2>/dev/null)
check "100 spheres poured, cells: exit 0 (got $rc), settled, no collision after step 2000 (last: ${last:-none}; held spheres on spheres asked: 4.5 M collisions in the last 500 steps)" \
    "[ $rc -eq 0 ] && [ -n '$last' ] && [ '$last' -le 2000 ]"

# A bouncier pour: 120 spheres (e = 0.9, steps of 20 ms) into a 0.53 m box, run to step 125.
# Two held spheres that rested on each other (each had gathered the other, already held, into
# its pocket) held each other: each one's landing let the other go, which landed again at the
# same instant, 100000 times, and the run stopped ("events do not resolve": seed 3 at step 117,
# seed 2 at step 123 with the pocket's check alone taken out; since held spheres move under
# pushes their pile cannot take, 2026-12-02, seeds 4, 5 and 8 at steps 121 to 124, and this is
# seed 4). A held sphere that rests on
# the sphere landing is no longer gathered into its pocket, nor landed on.
cat >"$tmp/pour.deck" <<'DECK'
run: { algorithm = "predictive"; steps = 125; dt = 2.0e-2; seed = 4; neighbors = "grid"; };
physics: { gravity = [0.0, 0.0, -9.81]; restitution = 0.9; };
box: { min = [0.0, 0.0, 0.0]; max = [0.53, 0.53, 3.0]; };
spheres = ( { count = 120; radius = 0.05; mass = 1.0; place = "random"; speed = 0.0; } );
output: { file = "pour.h5"; every = 10; fields = ["position", "velocity"]; };
DECK
for t in 1 2; do
    timeout -k 5 120 bin/nbep run "$tmp/pour.deck" --quiet -t "$t" -o "$tmp/pour-$t.h5" \
        2>"$tmp/pour-$t.err"
    rc=$?
    check "120 spheres poured at e = 0.9, grid, $t thread(s): 125 steps, exit 0 (got $rc; without the pocket's check: stopped at step 121)" \
        "[ $rc -eq 0 ] && [ ! -s '$tmp/pour-$t.err' ]"
done
check "120 spheres poured at e = 0.9, grid: frames identical for 1 and 2 threads" \
    "h5diff -q '$tmp/pour-1.h5' '$tmp/pour-2.h5' /frames /frames >/dev/null 2>&1"

# A row that fits its edge exactly, under gravity tilted into the edge's end (a pile poured into
# a box's corner): five held spheres on the floor along the y-max wall, 0.3 m long, gravity
# [2, 1, -9] pressing them towards the x-max wall, and a sixth dropped onto the middle one. The
# impact wakes the row, which passes its momentum to and fro at zero time (elastic by the TC
# model). Its spheres' planes do not carry them (gravity's x part is carried by the next sphere),
# so the jam hold took none, and the run stopped at run.max_reactions (step 217, every mode; a
# 100-sphere pour into a 0.3 m box with this gravity stopped so at step 505). Now a jammed sphere
# that meets a held one, however fast, is held on it too, and the row is held in turn.
cat >"$tmp/row.deck" <<'DECK'
run: { algorithm = "predictive"; steps = 300; dt = 1.0e-3; seed = 1; neighbors = "cells";
       max_reactions = 20000; };
physics: { gravity = [2.0, 1.0, -9.0]; restitution = 0.5; };
box: { min = [0.0, 0.0, 0.0]; max = [0.3, 0.3, 0.6]; };
spheres = ( { position = [0.03, 0.27, 0.03]; radius = 0.03; mass = 1.0; },
            { position = [0.09, 0.27, 0.03]; radius = 0.03; mass = 1.0; },
            { position = [0.15, 0.27, 0.03]; radius = 0.03; mass = 1.0; },
            { position = [0.21, 0.27, 0.03]; radius = 0.03; mass = 1.0; },
            { position = [0.27, 0.27, 0.03]; radius = 0.03; mass = 1.0; },
            { position = [0.10, 0.25, 0.3]; radius = 0.03; mass = 1.0; } );
output: { file = "row.h5"; every = 50; fields = ["position", "velocity"]; };
DECK
for mode in cells grid all; do
    timeout -k 5 60 bin/nbep run "$tmp/row.deck" --quiet -t 1 -o "$tmp/row-$mode.h5" \
        --set "run.neighbors=\"$mode\"" 2>"$tmp/row-$mode.err"
    rc=$?
    check "a row that fits its edge, tilted gravity, $mode: exit 0 (got $rc; before: run.max_reactions at step 217)" \
        "[ $rc -eq 0 ] && [ ! -s '$tmp/row-$mode.err' ]"
    h=$("$PY" -c 'import sys, h5py, numpy as np
f = h5py.File(sys.argv[1], "r")
v = f["/frames/velocity"][-1][:5]
print(int((np.abs(v).sum(axis=1) == 0.0).sum()) if f["/frames/step"][-1] == 300 else -1)' \
        "$tmp/row-$mode.h5" 2>/dev/null)
    check "a row that fits its edge, tilted gravity, $mode: the 5 of the row held at step 300 (got ${h:-none})" \
        "[ '${h:-0}' -eq 5 ]"
done
timeout -k 5 60 bin/nbep run "$tmp/row.deck" --quiet -t 2 --set 'run.neighbors="grid"' \
    -o "$tmp/row-grid-2.h5" 2>/dev/null
check "a row that fits its edge, tilted gravity, grid: frames identical for 1 and 2 threads" \
    "h5diff -q '$tmp/row-grid.h5' '$tmp/row-grid-2.h5' /frames /frames >/dev/null 2>&1"

# The same row falling: in mid-air against the x-max wall and spanning the box from y-min to
# y-max (five spheres of diameter 0.06 in 0.3 m, touching), gravity [2, 1, -9]. Nothing carries
# it, so neither holding rule applies; pressed into the y-max wall, its spheres met one another
# at zero time for ever (the TC model makes the meetings elastic, the minimum bounce feeds them),
# and the run stopped at run.max_reactions in step 1 in every mode (a 100-sphere pour into a
# 0.3 x 0.3 x 1.2 box stopped so at step 887 in cells mode). Now jammed spheres that meet move
# on as one body (jam_lock; README, granular scenes): the row falls whole, lands, bounces and
# is held on the floor, every sphere where the walls keep it in y and x.
cat >"$tmp/fall.deck" <<'DECK'
run: { algorithm = "predictive"; steps = 600; dt = 1.0e-3; seed = 1; neighbors = "cells";
       max_reactions = 20000; };
physics: { gravity = [2.0, 1.0, -9.0]; restitution = 0.5; };
box: { min = [0.0, 0.0, 0.0]; max = [0.3, 0.3, 0.3]; };
spheres = ( { position = [0.27, 0.03, 0.2]; radius = 0.03; mass = 1.0; },
            { position = [0.27, 0.09, 0.2]; radius = 0.03; mass = 1.0; },
            { position = [0.27, 0.15, 0.2]; radius = 0.03; mass = 1.0; },
            { position = [0.27, 0.21, 0.2]; radius = 0.03; mass = 1.0; },
            { position = [0.27, 0.27, 0.2]; radius = 0.03; mass = 1.0; } );
output: { file = "fall.h5"; every = 50; fields = ["position", "velocity"]; };
DECK
timeout -k 5 60 bin/nbep run "$tmp/fall.deck" --quiet -t 1 -o "$tmp/fall.h5" \
    --summary "$tmp/fall.json" 2>"$tmp/fall.err"
rc=$?
check "a falling row that fits its edge, cells: exit 0 (got $rc; before: run.max_reactions at step 1)" \
    "[ $rc -eq 0 ] && [ ! -s '$tmp/fall.err' ]"
# every frame: the row in its line (y and x as placed, to 1e-12 m: the walls allow no more),
# never above its start, its energy never above the start's; the last frame: all five held
# on the floor
f=$("$PY" -c 'import sys, h5py, numpy as np
f = h5py.File(sys.argv[1], "r")
p, v = f["/frames/position"][:], f["/frames/velocity"][:]
y0 = np.array([0.03, 0.09, 0.15, 0.21, 0.27])
line = np.abs(p[:, :, 1] - y0).max() <= 1e-12 and np.abs(p[:, :, 0] - 0.27).max() <= 1e-12
e = (0.5 * (v ** 2).sum(axis=2) - (p @ np.array([2.0, 1.0, -9.0]))).sum(axis=1)
held = int((np.abs(v[-1]).sum(axis=1) == 0.0).sum())
print(int(line), int(bool((p[:, :, 2] <= 0.2).all()) and bool((e <= e[0] * (1 + 1e-12)).all())),
      held, "%.9f" % p[-1, :, 2].max(), f["/frames/step"][-1])' "$tmp/fall.h5" 2>/dev/null)
set -- ${f:-0 0 0 0 0}
check "a falling row, cells: its spheres stay in their line in every frame to step 600" \
    "[ '$1' = 1 ] && [ '$5' = 600 ]"
check "a falling row, cells: no sphere rises above its start, no energy gained, to step 600" \
    "[ '$2' = 1 ] && [ '$5' = 600 ]"
check "a falling row, cells: all 5 held on the floor at step 600 (got $3 held, highest z $4, step $5)" \
    "[ '$3' = 5 ] && [ '$4' = 0.030000000 ] && [ '$5' = 600 ]"
timeout -k 5 60 bin/nbep run "$tmp/fall.deck" --quiet -t 2 -o "$tmp/fall-2.h5" 2>/dev/null
check "a falling row, cells: frames identical for 1 and 2 threads" \
    "h5diff -q '$tmp/fall.h5' '$tmp/fall-2.h5' /frames /frames >/dev/null 2>&1"
# grid and all-pairs modes make the bodies at a round's end, on one thread, the pairs in the
# order of their keys (lock_phase): the same row; and the same frames on 1, 2 and 3 threads to
# step 200, past the locks of step 1 and the landing (each run of the step-1 jam is some 10^4
# rounds: on 3 threads sharing 2 busy cores one took 100 s for 600 steps, so 200 here)
for mode in grid all; do
    timeout -k 5 60 bin/nbep run "$tmp/fall.deck" --quiet -t 1 --set "run.neighbors=\"$mode\"" \
        -o "$tmp/fall-$mode.h5" 2>"$tmp/fall-$mode.err"
    rc=$?
    f=$("$PY" -c 'import sys, h5py, numpy as np
f = h5py.File(sys.argv[1], "r")
p, v = f["/frames/position"][:], f["/frames/velocity"][:]
line = np.abs(p[:, :, 1] - np.array([0.03, 0.09, 0.15, 0.21, 0.27])).max() <= 1e-12
print(int(line), int((np.abs(v[-1]).sum(axis=1) == 0.0).sum()), f["/frames/step"][-1])' \
        "$tmp/fall-$mode.h5" 2>/dev/null)
    set -- ${f:-0 0 0}
    check "a falling row, $mode: exit 0, in its line, all 5 held at step 600 (exit $rc; in line $1, $2 held, step $3; before: run.max_reactions at step 1)" \
        "[ $rc -eq 0 ] && [ ! -s '$tmp/fall-$mode.err' ] && [ '$1' = 1 ] && [ '$2' = 5 ] && [ '$3' = 600 ]"
    for t in 1 2 3; do
        timeout -k 5 120 bin/nbep run "$tmp/fall.deck" --quiet -t "$t" -n 200 \
            --set "run.neighbors=\"$mode\"" -o "$tmp/fall-$mode-$t.h5" 2>/dev/null
    done
    check "a falling row, $mode: frames identical for 1, 2 and 3 threads to step 200" \
        "h5diff -q '$tmp/fall-$mode-1.h5' '$tmp/fall-$mode-2.h5' /frames /frames >/dev/null 2>&1 &&
         h5diff -q '$tmp/fall-$mode-1.h5' '$tmp/fall-$mode-3.h5' /frames /frames >/dev/null 2>&1"
done

# A body takes in every sphere in the jam (in_jam: a tenth of JAM_HOLD reactions in the step),
# not only the jammed ones: the row's ends react less often than its middle, and left out of
# the body they fed it their minimum bounces again at once; the middle pair, locked again and
# again, stopped at run.max_reactions = 11000 in step 1 in every mode.
for mode in cells grid all; do
    timeout -k 5 60 bin/nbep run "$tmp/fall.deck" --quiet -t 1 -n 100 --set "run.neighbors=\"$mode\"" \
        --set run.max_reactions=11000 -o "$tmp/fall11-$mode.h5" 2>"$tmp/fall11-$mode.err"
    rc=$?
    check "a falling row at run.max_reactions = 11000, $mode: its ends join the body, 100 steps run (exit $rc; before: run.max_reactions at step 1)" \
        "[ $rc -eq 0 ] && [ ! -s '$tmp/fall11-$mode.err' ]"
done

# A body holds at most LOCK_MAX = 64 spheres (jam_lock; README, *Jammed bodies*): the same
# falling row, 64 and 65 spheres long, each spanning its box from y-min to y-max. Every sphere
# is in the jam at step 1, so the 64 make one body, which falls freely as one until it lands
# (near t = 0.19 s): in its line, against the x-max wall, at z = 0.2 - 4.5 t^2 (its gravity
# along z is -9; the walls take the rest). The 65 make none (the walk stops at its 65th sphere:
# no lock, no sphere moved) and meet as they would without locks: pressed together, at zero
# time, as the row of 5 did before the locks, until run.max_reactions stops the run within a
# microsecond of step 1's start (2.4e-7 s; 3.3e-7 and 5.9e-7 s for rows of 70 and 130). A lock
# of the first 64 alone moves them on as a body, and the 65th stops the run later (6.2e-5 s:
# under 1e-5 s says no body moved). (Measured 2026-12-04: under 2 s each.)
# long_row N: that row of N spheres run to step 150 in cells mode into $tmp/longN.{h5,err}, rc
long_row() {
    "$PY" -c 'import sys
n = int(sys.argv[1])
print("run: { algorithm = \"predictive\"; steps = 150; dt = 1.0e-3; seed = 1; neighbors = \"cells\";")
print("       max_reactions = 20000; };")
print("physics: { gravity = [2.0, 1.0, -9.0]; restitution = 0.5; };")
print("box: { min = [0.0, 0.0, 0.0]; max = [0.3, %r, 0.3]; };" % (n * 0.06))
print("spheres = (" + ",\n".join("{ position = [0.27, %r, 0.2]; radius = 0.03; mass = 1.0; }"
                                 % (0.03 + 0.06 * k) for k in range(n)) + ");")
print("output: { file = \"row.h5\"; every = 50; fields = [\"position\"]; };")' "$1" >"$tmp/long$1.deck"
    timeout -k 5 60 bin/nbep run "$tmp/long$1.deck" --quiet -t 1 -o "$tmp/long$1.h5" \
        2>"$tmp/long$1.err"
    rc=$?
}
long_row 64
f=$("$PY" -c 'import sys, h5py, numpy as np
f = h5py.File(sys.argv[1], "r")
t, p = f["/frames/time"][:], f["/frames/position"][:]
line = np.abs(p[:, :, 1] - (0.03 + 0.06 * np.arange(64))).max()
wall = np.abs(p[:, :, 0] - 0.27).max()
fall = np.abs(p[:, :, 2] - (0.2 - 4.5 * t[:, None] ** 2)).max()
print(len(t), "%.3g" % max(line, wall), "%.3g" % fall)' "$tmp/long64.h5" 2>/dev/null)
set -- ${f:-0 1 1}
check "a falling row of 64 (LOCK_MAX), cells: one body, exit 0, in its line and falling freely to step 150 ($1 frames, off the line by $2 m, the fall by $3 m; exit $rc)" \
    "[ $rc -eq 0 ] && [ ! -s '$tmp/long64.err' ] && [ '$1' = 4 ] &&
     awk 'BEGIN { exit !($2 <= 1e-12 && $3 <= 1e-9) }'"
long_row 65
at=$(sed -n 's/.* in one step (t = \([^,]*\), run.max_reactions).*/\1/p' "$tmp/long65.err")
check "a falling row of 65, one past LOCK_MAX, cells: no body; run.max_reactions stops it at step 1, t = ${at:-?} s, under 1e-5 s (exit $rc)" \
    "[ $rc -eq 1 ] && [ \$(wc -l <'$tmp/long65.err') = 1 ] &&
     grep -q '^nbep: step 1: sphere [0-9]* reacted over 20000 times in one step' '$tmp/long65.err' &&
     awk 'BEGIN { exit !(${at:-1} < 1e-5) }'"

# The falling row with its spheres rising and falling at different speeds ([0.02, 0, 0.01,
# 0.03, -0.01] m/s), all leaving the x-max wall at 0.1 m/s: the body each lock makes takes its
# members' mean velocity, so no impulse but gravity's acts along z before the row reaches the
# floor (t = 0.1 s here): the row's momentum along z is 0.05 - 5 x 9 t kg m/s in every frame
# until then, to round-off (a lock that took the mean of the meeting pair alone would break it
# by about 0.01). And it leaves the wall, which it touched at the lock, faster than the rest
# speed, so the wall is no contact of its: gravity's 2 m/s^2 brings it back, and at t = 0.05 s
# it is at x = 0.27 - 0.1 t + t^2 = 0.2675 (a lock that kept the wall would have stopped it
# there, at 0.27).
sed -e 's/0.2\]; radius/0.2]; velocity = [-0.1, 0.0, VZ]; radius/' "$tmp/fall.deck" |
    awk 'BEGIN { split("0.02 0.0 0.01 0.03 -0.01", vz) } /VZ/ { sub("VZ", vz[++k]) } { print }' \
    >"$tmp/fallv.deck"
timeout -k 5 60 bin/nbep run "$tmp/fallv.deck" --quiet -t 1 -o "$tmp/fallv.h5" 2>"$tmp/fallv.err"
rc=$?
m=$("$PY" -c 'import sys, h5py, numpy as np
f = h5py.File(sys.argv[1], "r")
t, v = f["/frames/time"][:], f["/frames/velocity"][:]
k = t <= 0.1
x = f["/frames/position"][:][np.abs(t - 0.05) < 1e-9][0][:, 0]
print("%d %.3g %.9f" % (k.sum(), np.abs(v[k, :, 2].sum(axis=1) - (0.05 - 45.0 * t[k])).max(),
                        np.abs(x - 0.2675).max()))' "$tmp/fallv.h5" 2>/dev/null)
set -- ${m:-0 1 1}
check "a falling row with different speeds along z, cells: exit 0 (got $rc)" \
    "[ $rc -eq 0 ] && [ ! -s '$tmp/fallv.err' ]"
check "a falling row with different speeds along z: its z momentum kept in the $1 frames to t = 0.1 (off by $2)" \
    "[ '$1' -ge 3 ] && awk 'BEGIN { exit !($2 <= 1e-12) }'"
check "a falling row leaving the wall it touched: back to x = 0.2675 at t = 0.05 s (off by $3 m)" \
    "awk 'BEGIN { exit !($3 <= 1e-6) }'"

# Heading into that wall at 0.1 m/s instead: the row bounces off it (e = 0.5) before it jams,
# and its bodies then meet the sphere at the row's end, which rests on the y-max wall, each
# of the two leaning on a wall across from the other (the body's sphere on that same wall,
# through the end sphere, a contact of the body's). Neither can move along their line of
# centres, and the pair's response divided an impulse by the round-off that the walls leave
# of that line (1e-17, squared): the two flew off at 1.5e5 m/s and the energy rose 20-fold.
# Now that round-off counts as nothing. Run on, it stopped at run.max_reactions at step 51
# until the body took in the spheres in the jam (in_jam); then at step 51 the end sphere was
# shot off at 1.9 m/s, the energy up by a third: the body's sphere, moving across the wall it
# keeps through the end sphere, met that sphere closing at 1e-8 m/s along a line its planes
# left 3e-9 of, and the response's impulse grew as the inverse square. A response never adds
# energy now (nbep_physics_respond_pair_along). All 600 steps, in every mode.
sed -e 's/0.2\]; radius/0.2]; velocity = [0.1, 0.0, 0.0]; radius/' "$tmp/fall.deck" >"$tmp/fallin.deck"
for mode in cells grid all; do
    timeout -k 5 60 bin/nbep run "$tmp/fallin.deck" --quiet -t 1 --set "run.neighbors=\"$mode\"" \
        -o "$tmp/fallin-$mode.h5" 2>"$tmp/fallin-$mode.err"
    rc=$?
    m=$("$PY" -c 'import sys, h5py, numpy as np
f = h5py.File(sys.argv[1], "r")
p, v = f["/frames/position"][:], f["/frames/velocity"][:]
e = (0.5 * (v ** 2).sum(axis=2) - (p @ np.array([2.0, 1.0, -9.0]))).sum(axis=1)
print("%.6g %d" % (e.max() / e[0], f["/frames/step"][-1]))' "$tmp/fallin-$mode.h5" 2>/dev/null)
    set -- ${m:-9 0}
    check "a falling row bouncing off the wall it touched, $mode: 600 steps, its energy never above the start's (max/start $1, exit $rc, step $2; before: 1.31 at step 51, or run.max_reactions)" \
        "[ $rc -eq 0 ] && [ ! -s '$tmp/fallin-$mode.err' ] && [ '$2' = 600 ] && awk 'BEGIN { exit !($1 <= 1 + 1e-12) }'"
done

# 100 spheres poured into the corner of a 0.3 x 0.3 x 1.2 m box under gravity [2, 1, -9] (cells
# mode, seeds 1 and 3; rows of five fit the box's floor and walls exactly): before jammed
# spheres moved as one body, run.max_reactions (20000 here) stopped them at steps 591 and 361
# (at the default 1e6, seed 1 at step 887). Seed 3 also needs the body to keep a wall it leaves
# slower than the rest speed as a contact (dropped, the body fell back into it at once and the
# run stopped at step 512).
sed -e 's/steps = 600;/steps = 900;/' -e 's/max = \[0.3, 0.3, 0.3\]/max = [0.3, 0.3, 1.2]/' \
    -e '/^spheres = /,/^output/d' "$tmp/fall.deck" >"$tmp/corner.deck"
cat >>"$tmp/corner.deck" <<'DECK'
spheres = ( { count = 100; radius = 0.03; mass = 1.0; place = "random"; speed = 0.0; } );
output: { file = "corner.h5"; every = 100; fields = []; };
DECK
for seed in 1 3; do
    steps=$([ "$seed" = 1 ] && echo 900 || echo 600)
    # (seed 1 about 14 s alone: a hang's limit, as the pile of 100's above)
    timeout -k 5 180 bin/nbep run "$tmp/corner.deck" --quiet -t 1 -n "$steps" \
        --set "run.seed=$seed" -o "$tmp/corner-$seed.h5" 2>"$tmp/corner-$seed.err"
    rc=$?
    check "100 spheres poured into a corner, seed $seed, cells: $steps steps, exit 0 (got $rc: $(head -c 200 "$tmp/corner-$seed.err"))" \
        "[ $rc -eq 0 ] && [ ! -s '$tmp/corner-$seed.err' ]"
done

# An inverted square pyramid of four planes meeting at a point (a new user's hopper), 5 spheres
# dropped in (e = 0.5): until 2026-12-01 one that slid up an edge of two planes and stopped
# there still had the 5e-16 m/s across each plane left from when it was fast, against 3e-6 m/s
# along the edge; the contact test, relative to its speed alone, made it leave each plane as it
# met the other, in turn at zero time, and run.max_reactions stopped the run (cells mode at
# step 1963, all pairs at 1900; a pour of 60 in every mode). Now it runs on, and by step 4000
# every sphere is held,
# none below a plane by more than round-off.
cat >"$tmp/pyramid.deck" <<'DECK'
run: { steps = 4000; dt = 1.0e-3; seed = 1; max_reactions = 20000; };
physics: { gravity = [0.0, 0.0, -9.81]; restitution = 0.5; };
planes = ( { normal = [1.0, 0.0, 1.0]; point = [0.0, 0.0, 0.0]; },
           { normal = [-1.0, 0.0, 1.0]; point = [0.0, 0.0, 0.0]; },
           { normal = [0.0, 1.0, 1.0]; point = [0.0, 0.0, 0.0]; },
           { normal = [0.0, -1.0, 1.0]; point = [0.0, 0.0, 0.0]; } );
spheres = ( { position = [-0.0146, -0.1867, 1.0012]; radius = 0.05; mass = 1.0; },
            { position = [0.1077, 0.0489, 0.6946]; radius = 0.05; mass = 1.0; },
            { position = [-0.1978, -0.0705, 1.1728]; radius = 0.05; mass = 1.0; },
            { position = [0.2847, 0.24, 1.2526]; radius = 0.05; mass = 1.0; },
            { position = [0.0743, -0.3558, 1.0106]; radius = 0.05; mass = 1.0; } );
output: { file = "pyramid.h5"; every = 50; };
DECK
for mode in cells grid all; do
    timeout -k 5 60 bin/nbep run "$tmp/pyramid.deck" --quiet -t 1 --set "run.neighbors=\"$mode\"" \
        -o "$tmp/pyramid-$mode.h5" 2>"$tmp/pyramid-$mode.err"
    rc=$?
    m=$("$PY" -c 'import sys, h5py, numpy as np
f = h5py.File(sys.argv[1], "r")
p = f["/frames/position"][-1]
n = np.array([[1, 0, 1], [-1, 0, 1], [0, 1, 1], [0, -1, 1]]) / np.sqrt(2.0)
print("%.3g %d" % (((p @ n.T) - 0.05).min() / 0.05, f["/frames/step"][-1]))' "$tmp/pyramid-$mode.h5" 2>/dev/null)
    set -- ${m:-9 0}
    check "5 spheres in a pyramid of four planes, $mode: 4000 steps, exit 0 (got $rc: $(head -c 160 "$tmp/pyramid-$mode.err")), all 5 held ($(held "$tmp/pyramid-$mode.h5")), none below a plane (least gap / r $1)" \
        "[ $rc -eq 0 ] && [ '$2' = 4000 ] && [ \$(held '$tmp/pyramid-$mode.h5') = 5 ] &&
         awk 'BEGIN { exit !($1 >= -1e-12) }'"
done

# ... and at a smaller step: the first mend reckoned the round-off against |a| dt, which at
# dt = 3e-5 fell below the 5e-16 m/s left across the planes, and cells mode stopped on
# run.max_reactions at t = 1.58 (a review, frames every 1666 steps: in cells mode the frame
# interval sets the round-off, and with it where such a jam comes); the speed of a fall
# through a radius does not depend on dt
timeout -k 5 120 bin/nbep run "$tmp/pyramid.deck" --quiet -t 1 --set 'run.neighbors="cells"' \
    --set run.dt=3e-5 --set run.steps=60000 --set output.every=1666 \
    -o "$tmp/pyramid-small-dt.h5" 2>"$tmp/pyramid-small-dt.err"
rc=$?
check "the pyramid at dt = 3e-5, cells: to t = 1.8 (60000 steps), exit 0 (got $rc: $(head -c 160 "$tmp/pyramid-small-dt.err"))" \
    "[ $rc -eq 0 ] && [ ! -s '$tmp/pyramid-small-dt.err' ]"

# A pair that would lock (lockable) whose body is past LOCK_MAX meets as any pair, in the
# rounds modes as in cells mode (nbep__pred_react, lock_phase): a pile of 100 poured at
# dt = 0.05 in grid mode (seed 2) jams at step 12 with more than 64 spheres in the jam. Until
# 2026-12-04 the rounds modes gave such a pair no response at all, so it met again at the same
# time for ever, and the stall check stopped the run at step 12 (`events at t = 0.5988 do not
# resolve`, after 21 s; all pairs: a pile of 100 in a 0.3 m cube, step 14). Now it runs on,
# the same frames on 1 and 2 threads. (Measured 2026-12-04: about 6 s each.)
cat >"$tmp/coarse-pile.deck" <<'EOF'
run: { algorithm = "predictive"; steps = 13; dt = 0.05; seed = 2; neighbors = "grid"; };
physics: { gravity = [0.0, 0.0, -9.81]; restitution = 0.5; };
box: { min = [0.0, 0.0, 0.0]; max = [0.3, 0.3, 0.6]; };
spheres = ( { count = 100; radius = 0.03; mass = 1.0; place = "random"; speed = 0.0; } );
output: { file = "coarse-pile.h5"; every = 1; fields = ["position", "velocity"]; };
EOF
for t in 1 2; do
    timeout -k 5 120 bin/nbep run "$tmp/coarse-pile.deck" --quiet -t $t -o "$tmp/coarse-pile-$t.h5" \
        2>"$tmp/coarse-pile-$t.err"
    rc=$?
    check "a pile of 100 at dt = 0.05, grid, $t thread(s): a jam past LOCK_MAX meets as any pair, 13 steps (exit $rc: $(head -c 160 "$tmp/coarse-pile-$t.err"))" \
        "[ $rc -eq 0 ] && [ ! -s '$tmp/coarse-pile-$t.err' ]"
done
check "a pile of 100 at dt = 0.05, grid: the same frames on 1 and 2 threads" \
    "h5diff -q '$tmp/coarse-pile-1.h5' '$tmp/coarse-pile-2.h5' /frames /frames >/dev/null 2>&1"

# A held sphere without contacts that a response moves is held no more (update_rest): a mixture
# of radii 0.02 and 0.04 poured at dt = 0.05 under tilted gravity, e = 0, grid mode, seed 1
# (a helper's sweep). Until 2026-12-04 such a sphere stayed held while moving, met two held
# neighbours at zero time, each let go and held again in turn, and the stall check stopped the
# run at step 17 (t = 0.8354, after 9 s). (Measured 2026-12-04: 8.5 s.)
cat >"$tmp/coarse-mix.deck" <<'EOF'
run: { algorithm = "predictive"; steps = 18; dt = 0.05; seed = 1; neighbors = "grid"; };
physics: { gravity = [2.0, 1.0, -9.0]; restitution = 0.0; };
box: { min = [0.0, 0.0, 0.0]; max = [0.358, 0.358, 0.6]; };
spheres = ( { count = 40; radius = 0.02; mass = 0.3; place = "random"; speed = 0.0; },
            { count = 40; radius = 0.04; mass = 2.4; place = "random"; speed = 0.0; } );
output: { file = "coarse-mix.h5"; every = 18; fields = ["position"]; };
EOF
timeout -k 5 120 bin/nbep run "$tmp/coarse-mix.deck" --quiet -t 1 -o "$tmp/coarse-mix.h5" \
    2>"$tmp/coarse-mix.err"
rc=$?
check "a tilted mixture at dt = 0.05, grid: a held sphere that a response moves is let go, 18 steps (exit $rc: $(head -c 160 "$tmp/coarse-mix.err"))" \
    "[ $rc -eq 0 ] && [ ! -s '$tmp/coarse-mix.err' ]"
exit $fail
