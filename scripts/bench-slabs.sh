#!/usr/bin/env bash
# What per-slab calendars cost the one-thread event loop (NBEP_SLABS; step 1 of
# docs/optimistic-design.md: the calendar cut into slabs across x, their earliest entries
# merged on one thread, the results the same bit for bit): bin/nbep with one calendar beside
# itself with S slabs, paired by scripts/ab-pair.sh (both at once, one a core, swapping cores
# each repeat; the median of the repeats' own ratios), on a melted hard-sphere fluid.
#
#   scripts/bench-slabs.sh [COUNT PHI]          (default 32000 0.30)
#
# Environment:
#   SLABS  slab counts (default "2 4 16")
#   REPS   repeats of each pair (default 5)
#   STEPS  the timed stretch, in steps of the deck's dt = 0.1 after a melt of 20 (default 20)
#   OUT    scratch folder (default build/bench-slabs)
#   THREADS N (N >= 2): instead of pairs, the slabs on N threads through the optimistic
#          scheduler (NBEP_SCHEDULED=1 with NBEP_SLABS; slabs on threads of their own, the
#          results the same): each repeat runs, one after the other, the plain loop on one
#          thread, the team loop on N and the scheduled loop on each slab count on N (all N
#          threads at once: no pairs), and a figure is the median over repeats of the plain
#          loop's stepping seconds over its own (a speed-up: above 1 is faster)
#   SERIAL 1: instead of pairs, each repeat runs one calendar and then every slab count one
#          after the other on one CPU (taskset -c CPU, default 0), and a count's figure is the
#          median over repeats of its stepping loop's seconds (the summary's wall_seconds)
#          over the one calendar's of the same repeat; the two cores of a shared virtual
#          machine can differ more than two minutes on one do
# Prints, per slab count, the medians, the median ratio (slabs over one calendar) with every
# repeat's, and whether the collision counts agreed (they must).
set -eu
cd "$(dirname "$0")/.." || exit 1
count=${1:-32000}
phi=${2:-0.30}
SLABS=${SLABS:-2 4 16}
REPS=${REPS:-5}
STEPS=${STEPS:-20}
OUT=${OUT:-build/bench-slabs}
[ -x bin/nbep ] || { echo "bench-slabs: bin/nbep missing: make" >&2; exit 2; }
mkdir -p "$OUT"
side=$(awk -v n="$count" -v p="$phi" 'BEGIN { printf "%.10f", (n * atan2(0, -1) / 6 / p) ^ (1 / 3) }')
# the example deck at this count and fraction, 20 + STEPS steps (a resume needs the deck that
# wrote the melt, with more steps), threads 1 (ab-pair.sh runs one thread a core)
deck="$OUT/fluid-$count-$phi.deck"
sed -e "s/count = 32000;/count = $count;/" \
    -e "s/max = \[[0-9.]*, [0-9.]*, [0-9.]*\];/max = [$side, $side, $side];/" \
    -e "s/steps = [0-9]*;/steps = $((20 + STEPS));/" -e "s/threads = [0-9]*;/threads = 1;/" \
    -e "s/file = \"[^\"]*\";/file = \"$(basename "$deck" .deck).h5\";/" \
    inputs/hard-sphere-fluid.deck >"$deck"
grep -q "count = $count;" "$deck" && grep -q "max = \[$side" "$deck" ||
    { echo "bench-slabs: inputs/hard-sphere-fluid.deck changed its form: edit this script" >&2; exit 1; }
melt="$OUT/melt-$count-$phi.h5"
if [ ! -f "$melt" ] || [ "$deck" -nt "$melt" ]; then
    echo "bench-slabs: melting $count spheres at phi = $phi (20 steps of 0.1 from the lattice)"
    bin/nbep run "$deck" -n 20 -o "$melt" -q
fi
# One timed resume of the melt by the command given (the rest of its command line: --resume and
# the summary), appended to $rows as NAME,REP,wall_seconds,collisions
timed_row() {
    local name=$1 rep=$2 w c
    shift 2
    cp "$melt" "$OUT/r.h5"
    "$@" --resume "$OUT/r.h5" -q --summary "$OUT/s.json"
    w=$(sed -n 's/.*"wall_seconds": *\([0-9.e+-]*\).*/\1/p' "$OUT/s.json")
    c=$(sed -n 's/.*"collisions": *\([0-9]*\).*/\1/p' "$OUT/s.json")
    echo "$name,$rep,$w,$c" >>"$rows"
}
if [ -n "${THREADS:-}" ]; then
    echo "bench-slabs: N = $count, phi = $phi, $STEPS steps of 0.1 after the melt, $REPS repeats, $THREADS threads"
    rows="$OUT/threads.csv"
    echo "way,rep,wall_seconds,collisions" >"$rows"
    for rep in $(seq "$REPS"); do
        for way in plain team $SLABS; do
            case $way in
            plain) timed_row "$way" "$rep" bin/nbep run "$deck" -t 1 ;;
            team) timed_row "$way" "$rep" bin/nbep run "$deck" -t "$THREADS" ;;
            *) timed_row "$way" "$rep" env NBEP_SCHEDULED=1 NBEP_SLABS="$way" bin/nbep run \
                   "$deck" -t "$THREADS" ;;
            esac
        done
    done
    python3 - "$rows" <<'PYEOF3'
import csv, statistics as st, sys
rows = list(csv.DictReader(open(sys.argv[1])))
base = {r["rep"]: r for r in rows if r["way"] == "plain"}
print("  plain loop, 1 thread: median %.3f s" % st.median(float(r["wall_seconds"]) for r in base.values()))
for way in dict.fromkeys(r["way"] for r in rows if r["way"] != "plain"):
    mine = [r for r in rows if r["way"] == way]
    R = [float(base[r["rep"]]["wall_seconds"]) / float(r["wall_seconds"]) for r in mine]
    same = all(r["collisions"] == base[r["rep"]]["collisions"] for r in mine)
    name = "team loop" if way == "team" else "%s slabs, scheduled" % way
    print("  %s: median %.3f s, speed-up median %.3f [%s]; same collisions: %s"
          % (name, st.median(float(r["wall_seconds"]) for r in mine), st.median(R),
             " ".join("%.3f" % x for x in R), same))
PYEOF3
    exit 0
fi
if [ "${SERIAL:-0}" = 1 ]; then
    echo "bench-slabs: N = $count, phi = $phi, $STEPS steps of 0.1 after the melt, $REPS repeats on CPU ${CPU:-0}"
    rows="$OUT/serial.csv"
    echo "slabs,rep,wall_seconds,collisions" >"$rows"
    for rep in $(seq "$REPS"); do
        for s in 1 $SLABS; do
            timed_row "$s" "$rep" env NBEP_SLABS="$s" taskset -c "${CPU:-0}" bin/nbep run "$deck"
        done
    done
    python3 - "$rows" <<'PYEOF2'
import csv, statistics as st, sys
rows = list(csv.DictReader(open(sys.argv[1])))
base = {r["rep"]: r for r in rows if r["slabs"] == "1"}
for s in sorted({int(r["slabs"]) for r in rows} - {1}):
    mine = [r for r in rows if r["slabs"] == str(s)]
    R = [float(r["wall_seconds"]) / float(base[r["rep"]]["wall_seconds"]) for r in mine]
    same = all(r["collisions"] == base[r["rep"]]["collisions"] for r in mine)
    print("  %d slabs: one calendar median %.3f s, slabs %.3f s, ratio median %.3f [%s]; "
          "same collisions: %s" % (s, st.median(float(base[r["rep"]]["wall_seconds"]) for r in mine),
                                   st.median(float(r["wall_seconds"]) for r in mine),
                                   st.median(R), " ".join("%.3f" % x for x in R), same))
PYEOF2
    exit 0
fi
echo "bench-slabs: N = $count, phi = $phi, $STEPS steps of 0.1 after the melt, $REPS pairs"
for s in $SLABS; do
    wrap="$OUT/nbep-slabs-$s"
    printf '#!/bin/sh\nNBEP_SLABS=%s exec "%s/bin/nbep" "$@"\n' "$s" "$PWD" >"$wrap"
    chmod +x "$wrap"
    echo "  $s slabs against one calendar:"
    scripts/ab-pair.sh "$REPS" "$deck" bin/nbep "$wrap" "$melt" | sed 's/^/    /'
done
