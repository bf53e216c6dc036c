#!/usr/bin/env bash
# Paired A/B timing of two nbep binaries on one deck, for a machine whose speed moves from
# minute to minute (this project's shared 2-core one: the same run takes 10 to 20 % longer or
# shorter from one minute to the next). A and B run at the same time, one per core
# (taskset), swapping cores each repeat, so that both meet the same load; the figure is the
# median over repeats of B's loop time over A's (the summary's wall_seconds), with the
# collision counts compared (the same bits when the change should not alter results).
# One thread per run: the deck's run.threads should be 1.
#
#   scripts/ab-pair.sh REPS DECK BIN_A BIN_B [MELT]
#   e.g. scripts/ab-pair.sh 8 inputs/hard-sphere-fluid.deck /tmp/nbep.old bin/nbep
#
# With MELT (an nbep output file, such as a melt of make bench-dense: build/bench-dense/
# melt-32000-0.50.h5 with its deck fluid-32000-0.50-80-1.deck), each run resumes a copy of it
# (--resume) instead of starting from the deck's own start: the equilibrium fluid, timed
# without the melting. The deck must be the one that wrote MELT, with more steps.
#
# Prints A's and B's median seconds, the median ratio B/A with every repeat's, and whether the
# collision counts agreed in every repeat; where they did not (a change that alters a granular
# scene's trajectories, which then collide more or less), also the median ratio of B's
# collisions per second to A's, the figure that compares them. Then, over each two repeats in
# turn (1 and 2, 3 and 4, ...: the same two cores, swapped), the geometric mean of their two
# ratios, and the median of those (at least 2 repeats). Where the two cores differ in speed
# (this project's machine: one took 1.9 s where the other took 2.8 s on the same run in the
# same minute, 2026-12-07), each repeat's ratio carries that difference one way or the other,
# in turn (1.74, 0.98, 1.79, 0.97, ... for a change costing about 1.3), and their median is
# whichever way the count of repeats tips; the pair's mean cancels a difference that holds
# over its two repeats. Outputs go to a temporary folder, removed after.
set -euo pipefail
if [ $# -ne 4 ] && [ $# -ne 5 ]; then
    echo "usage: scripts/ab-pair.sh REPS DECK BIN_A BIN_B [MELT]" >&2
    exit 2
fi
reps=$1 deck=$2 a=$3 b=$4 melt=${5:-}
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
for r in $(seq "$reps"); do
    if [ $((r % 2)) = 1 ]; then ca=0 cb=1; else ca=1 cb=0; fi
    if [ -n "$melt" ]; then # each resumes its own copy
        cp "$melt" "$tmp/a.h5"
        cp "$melt" "$tmp/b.h5"
    fi
    taskset -c $ca "$a" run "$deck" --output "$tmp/a.h5" ${melt:+--resume "$tmp/a.h5"} \
        --summary "$tmp/a.json" --quiet &
    pa=$!
    taskset -c $cb "$b" run "$deck" --output "$tmp/b.h5" ${melt:+--resume "$tmp/b.h5"} \
        --summary "$tmp/b.json" --quiet &
    pb=$!
    wait $pa
    wait $pb
    /usr/bin/python3 - "$tmp/a.json" "$tmp/b.json" "$tmp/a.h5" "$tmp/b.h5" "$melt" <<'PYEOF'
import json, sys, h5py
a, b = (json.load(open(p)) for p in sys.argv[1:3])
# a resumed run's summary counts from step 0 where its file keeps /frames/totals (builds since
# 2026-11-30), the melt's collisions too, which are taken off: the collisions of the stretch
def own(s, path):
    if not sys.argv[5]:
        return s["collisions"]
    with h5py.File(path, "r") as f, h5py.File(sys.argv[5], "r") as m:
        if "totals" not in f["frames"]:
            return s["collisions"]
        t = f["frames/totals"][len(m["frames/step"]) - 1]
        return s["collisions"] - int(t["sphere_collisions"]) - int(t["plane_collisions"])
ca, cb = own(a, sys.argv[3]), own(b, sys.argv[4])
print(a["wall_seconds"], b["wall_seconds"], ca == cb, ca, cb)
PYEOF
done | python3 -c '
import statistics as st, sys
rows = [l.split() for l in sys.stdin]
A = [float(r[0]) for r in rows]; B = [float(r[1]) for r in rows]
R = [b / a for a, b in zip(A, B)]
same = all(r[2] == "True" for r in rows)
print("A median %.3f s, B median %.3f s, B/A median %.3f [%s]; same collisions: %s"
      % (st.median(A), st.median(B), st.median(R), " ".join("%.3f" % x for x in R), same))
P = [(R[k] * R[k + 1]) ** 0.5 for k in range(0, len(R) - 1, 2)]
if P:
    print("B/A over each two repeats, the cores swapped (geometric mean): median %.3f [%s]"
          % (st.median(P), " ".join("%.3f" % x for x in P)))
if not same:
    C = [(float(r[4]) / b) / (float(r[3]) / a) for a, b, r in zip(A, B, rows)]
    print("collisions A %s, B %s; B/A collisions per second median %.3f [%s]"
          % (rows[0][3], rows[0][4], st.median(C), " ".join("%.3f" % x for x in C)))
'
