#!/usr/bin/env bash
# What two slabs of the optimistic scheme (docs/optimistic-design.md) could give at best on this
# machine, messages, waits and rollbacks aside: a periodic hard-sphere fluid of N spheres at
# packing fraction PHI, and the same fluid halved (N/2 spheres, the box's side divided by the
# cube root of 2), each melted from its lattice for 20 steps of 0.05. Each repeat then runs, for
# steps 20 to 30 resumed from its melt, the full fluid's plain loop alone on CPU 0 and alone on
# CPU 1, two halves at once (one per CPU) through the plain loop, and two halves at once
# through the scheduled loop (NBEP_SCHEDULED=1: what a slab's thread pays to be able to roll
# back). The figure, per repeat and as the median over repeats: the full run's time (the mean
# of its two CPUs') over the slower half's, for the plain halves and for the scheduled ones
# (2 would be two slabs at twice one thread; more than 2, half the data serving each half's
# events better than all of it serves all of them).
#
#   scripts/bench-halves.sh [REPS [N [PHI]]]      (defaults 6 256000 0.30)
#
# Needs taskset and CPUs 0 and 1; NBEP (default bin/nbep) is the binary, PYTHON (default python3)
# reads the summaries. The decks, melts and runs go to a temporary folder, removed after (KEEP=1
# keeps it and prints its name). Exit status 2 for arguments or a fluid nbep refuses (one line),
# 1 where a run fails or the halves' collisions differ.
set -euo pipefail
usage="usage: scripts/bench-halves.sh [REPS [N [PHI]]] (defaults 6 256000 0.30; NBEP=bin/nbep)"
if [ "${1:-}" = "--help" ] || [ "${1:-}" = "-h" ]; then
    echo "$usage"
    exit 0
fi
if [ $# -gt 3 ]; then
    echo "bench-halves.sh: at most three arguments; $usage" >&2
    exit 2
fi
reps=${1:-6} n=${2:-256000} phi=${3:-0.30}
nbep=${NBEP:-bin/nbep}
py=$(command -v "${PYTHON:-python3}" 2>/dev/null) || {
    echo "bench-halves.sh: ${PYTHON:-python3} not found (PYTHON names the Python to use)" >&2
    exit 2
}
if ! [[ $reps =~ ^[1-9][0-9]*$ ]] || ! [[ $n =~ ^[1-9][0-9]*$ ]] || [ $((n % 2)) != 0 ] ||
    [ "$n" -lt 16 ]; then
    echo "bench-halves.sh: REPS must be a count of repeats and N an even count of spheres" \
        "(16 or more): got '$reps' '$n'" >&2
    exit 2
fi
if ! "$py" -c "import sys; p = float(sys.argv[1]); sys.exit(not 0.0 < p <= 0.45)" "$phi" \
    2>/dev/null; then
    echo "bench-halves.sh: PHI must be a packing fraction above 0 and at most 0.45 (a lattice" \
        "start that melts): got '$phi'" >&2
    exit 2
fi
if ! command -v taskset >/dev/null || ! taskset -c 0 true 2>/dev/null ||
    ! taskset -c 1 true 2>/dev/null; then
    echo "bench-halves.sh: needs taskset and CPUs 0 and 1 (one run per CPU)" >&2
    exit 2
fi
[ -x "$nbep" ] || { echo "bench-halves.sh: $nbep is not built (make)" >&2; exit 2; }
nbep=$(cd "$(dirname "$nbep")" && pwd)/$(basename "$nbep")
tmp=$(mktemp -d)
if [ "${KEEP:-0}" = 1 ]; then echo "kept: $tmp"; else trap 'rm -rf "$tmp"' EXIT; fi
cd "$tmp"
# the full box's side for n spheres of diameter 1 at phi; the half's, for n/2
side() { "$py" -c "import math, sys; print(repr((int(sys.argv[1]) * math.pi / 6 / float(sys.argv[2])) ** (1 / 3)))" "$1" "$phi"; }
deck() { # NAME COUNT SIDE STEPS
    cat >"$1.deck" <<DECK
run: { algorithm = "predictive"; neighbors = "cells"; steps = $4; dt = 0.05; threads = 1; seed = 1; };
box: { min = [0.0, 0.0, 0.0]; max = [$3, $3, $3]; periodic = [true, true, true]; };
spheres = ( { count = $2; radius = 0.5; mass = 1.0; place = "lattice"; speed = 1.7320508075688772; } );
output: { file = "$1.h5"; every = 20; fields = ["position", "velocity"]; stats = false; };
DECK
}
lf=$(side "$n") lh=$(side $((n / 2)))
deck full-melt "$n" "$lf" 20
deck full "$n" "$lf" 30
deck half-melt $((n / 2)) "$lh" 20
deck half $((n / 2)) "$lh" 30
# the melts (nbep's own checks of the fluids: a box too small for cells, a lattice too full)
for m in full-melt half-melt; do
    if ! env -u NBEP_SCHEDULED "$nbep" run "$m.deck" --quiet 2>"$m.err"; then
        echo "bench-halves.sh: nbep refused the fluid of $n spheres (or its half) at packing" \
            "fraction $phi: $(head -n 1 "$m.err")" >&2
        exit 2
    fi
done
secs() { "$py" -c "import json, sys; print('%.4f' % json.load(open(sys.argv[1]))['wall_seconds'])" "$1"; }
coll() { "$py" -c "import json, sys; print(json.load(open(sys.argv[1]))['collisions'])" "$1"; }
# RUN NAME CPU TAG [ENV]: a resumed run of NAME's deck from its own copy of NAME's melt, its
# summary NAME.CPU.TAG.json
run() {
    rm -f "$1.$2.$3.json"
    cp "$1-melt.h5" "$1.$2.h5"
    env -u NBEP_SCHEDULED ${4:-} taskset -c "$2" "$nbep" run "$1.deck" --output "$1.$2.h5" \
        --resume "$1.$2.h5" --quiet --summary "$1.$2.$3.json" ||
        { echo "bench-halves.sh: the run of $1 on CPU $2 ($3) failed" >&2; return 1; }
}
# two runs of the half at once, one per CPU: TAG [ENV]
pair() {
    run half 0 "$@" &
    local a=$!
    run half 1 "$@" &
    local b=$!
    local ra=0 rb=0
    wait "$a" || ra=$?
    wait "$b" || rb=$?
    [ "$ra" = 0 ] && [ "$rb" = 0 ]
}
echo "N = $n, phi = $phi (box side $lf; halves: N = $((n / 2)), side $lh); steps 20 to 30 of 0.05"
echo "repeat  full alone, CPU 0 and 1 (s)  halves plain (s)  halves scheduled (s)  full/slower half: plain  scheduled"
rows=()
same=True
for r in $(seq "$reps"); do
    run full 0 plain
    f0=$(secs full.0.plain.json)
    run full 1 plain
    f1=$(secs full.1.plain.json)
    pair plain
    p0=$(secs half.0.plain.json) p1=$(secs half.1.plain.json)
    pair sched NBEP_SCHEDULED=1
    s0=$(secs half.0.sched.json) s1=$(secs half.1.sched.json)
    # every half the same run, the same collisions (the scheduled loop changes no result)
    c=$(for f in half.0.plain half.1.plain half.0.sched half.1.sched; do coll "$f.json"; done |
        sort -u | wc -l)
    [ "$c" = 1 ] || { echo "bench-halves.sh: the halves' collisions differ" >&2; same=False; }
    row=$("$py" -c "
import sys
f0, f1, p0, p1, s0, s1 = map(float, sys.argv[1:])
full = (f0 + f1) / 2
print('%.3f %.3f' % (full / max(p0, p1), full / max(s0, s1)))" "$f0" "$f1" "$p0" "$p1" "$s0" "$s1")
    rows+=("$row")
    printf '%6d  %s %s  %s %s  %s %s  %s\n' "$r" "$f0" "$f1" "$p0" "$p1" "$s0" "$s1" "$row"
done
printf '%s\n' "${rows[@]}" | "$py" -c "
import statistics, sys
rows = [tuple(map(float, l.split())) for l in sys.stdin if l.strip()]
p = [a for a, b in rows]
s = [b for a, b in rows]
print('median full/slower half over %d repeats: plain halves %.3f (%.3f to %.3f), scheduled halves %.3f (%.3f to %.3f)'
      % (len(rows), statistics.median(p), min(p), max(p), statistics.median(s), min(s), max(s)))"
echo "the halves' collisions the same in every run: $same"
[ "$same" = True ]
