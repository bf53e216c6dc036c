#!/usr/bin/env bash
# Thread scaling on one node: the paper's box in nbep's three predictive modes, and the dense
# fluids of `make bench-dense` (nbep beside EDMD), on 1, 2, 4, ... threads up to the node's
# cores. The README's figures for a 16-core node came from it (Benchmarks, Dense fluids and
# Threads on dense scenes).
#
#   scripts/bench-threads.sh
#   EDMD_DIR=/path/to/EDMD NBEP=kit/nbep scripts/bench-threads.sh   (kit: scripts/pack-kit.sh)
#
# Environment:
#   THREADS   thread counts (default 1 2 4 ... and the node's cores)
#   REPS      repeats, the outer loop (default 3)
#   SCALE     the dense fluids' stretches, as a fraction of make bench-dense's (default 0.25:
#             about 7 minutes on 16 cores with EDMD)
#   OUT       results (default build/bench-threads): paper.csv, dense-32000/ and
#             dense-256000/ as make bench-dense leaves them (rows.csv), and threads.png, the
#             speed-ups over one thread (scripts/plot_threads.py)
#   NBEP, EDMD_DIR, PYTHON: as for scripts/bench-dense.sh
#
# The paper's box (inputs/paper-box.deck, n = 32768 spheres of radius 0.05 in the 10 m box,
# gravity, e = 1, 100 steps of 1 ms; no per-sphere output): run.neighbors "grid" and "cells"
# three times at each thread count, "all" (the paper's algorithm, n = 16384: its set-up
# predicts all pairs, 8 s on one core) once. At the end, scripts/plot_threads.py prints its
# table (ms per step of the stepping loop, medians) and every series' speed-ups, and draws them.
set -u
cd "$(dirname "$0")/.." || exit 1
cores=$(nproc)
powers() { local n=1 l=""; while [ "$n" -lt "$1" ]; do l="$l $n"; n=$((n * 2)); done; echo "$l $1"; }
THREADS=${THREADS:-$(powers "$cores")}
REPS=${REPS:-3}
SCALE=${SCALE:-0.25}
OUT=${OUT:-build/bench-threads}
NBEP=${NBEP:-bin/nbep}
PY=${PYTHON:-/usr/bin/python3}
mkdir -p "$OUT"
echo "nbep thread scaling: threads $THREADS on $cores cores; $("$NBEP" --version)"

csv="$OUT/paper.csv"
echo "mode,n,threads,rep,wall_seconds,setup_seconds,collisions" >"$csv"
field() { sed -n "s/.*\"$1\": *\([0-9.e+-]*\).*/\1/p"; }
paper() { # mode n threads rep
    local s
    s=$("$NBEP" run inputs/paper-box.deck -n 100 -t "$3" -o "$OUT/paper.h5" --quiet --summary - \
        --set "spheres.[0].count=$2" --set "run.neighbors=\"$1\"" --set output.every=100 \
        --set 'output.fields=[]' --set output.stats=false) || { echo "nbep failed: paper box, $*" >&2; return 1; }
    echo "$1,$2,$3,$4,$(echo "$s" | field wall_seconds),$(echo "$s" | field setup_seconds),$(echo "$s" | field collisions)" >>"$csv"
}
for rep in $(seq "$REPS"); do
    for t in $THREADS; do
        paper grid 32768 "$t" "$rep"
        paper cells 32768 "$t" "$rep"
        [ "$rep" = 1 ] && paper all 16384 "$t" 1
    done
done

for n in 32000 256000; do
    phis="0.30"
    [ "$n" = 32000 ] && phis="0.30 0.50"
    OUT="$OUT/dense-$n" NS=$n PHIS="$phis" THREADS="$THREADS" REPS="$REPS" SCALE="$SCALE" \
        NBEP="$NBEP" scripts/bench-dense.sh
done
"$PY" scripts/plot_threads.py "$OUT" "$OUT/threads.png" ||
    echo "plot_threads: no figure (matplotlib missing?)" >&2
