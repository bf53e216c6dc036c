#!/usr/bin/env bash
# Prepared for a borrowed 16-core node on 2026-12-04 and NOT run there (run at the next loan:
# docs/figures/node16-1204b; no node was lent again
# that session; tried once here, one repeat): the team loop at 986178f (old) against 4268a25
# (new: a place's record on one cache line), N = 256000,
# phi = 0.30, resumed at T1 = 1 for 0.5 time units, NBEP_TEAM=always, 2, 4 and 16 threads,
# the two builds alternating (which first swapped each repeat), threads pinned. Runs from
# build/dev (docs/figures/node16-e053a30/prep.sh's kit) with nbep.old and nbep.new beside it:
#   OUT=/tmp/out bash docs/figures/node16-1204/ab.sh       rows in $OUT/ab.csv
# No repeat starts after LIMIT seconds (default 150).
set -u
cd "$(dirname "$0")/../../.." || exit 1
D=$PWD/build/dev
K=$D/kit/lib
LD=$(echo "$K"/ld-linux*)
R=${OUT:-/tmp/out}
W=/tmp/w
REPS=${REPS:-20}
LIMIT=${LIMIT:-150}
mkdir -p "$R" "$W"
export OMP_PLACES=cores OMP_PROC_BIND=close
field() { sed -n "s/.*\"$1\": *\([0-9.e+-]*\).*/\1/p"; }
L=$(awk 'BEGIN { printf "%.12g", (256000 * atan2(0, -1) / (6 * 0.30)) ^ (1 / 3) }')
deck() { # steps file
    cat >"$W/d$1.deck" <<E2
run: { algorithm = "predictive"; steps = $1; dt = 0.05; threads = 1; seed = 1; neighbors = "cells"; };
box: { min = [0.0, 0.0, 0.0]; max = [$L, $L, $L]; periodic = [true, true, true]; };
spheres = ( { count = 256000; radius = 0.5; mass = 1.0; place = "lattice"; speed = 1.7320508075688772; } );
output: { file = "$2"; every = 20; fields = ["position", "velocity"]; stats = false; };
E2
    echo "$W/d$1.deck"
}
t0=$(date +%s)
"$LD" --library-path "$K" "$D/nbep.new" run "$(deck 20 "$W/melt.h5")" -t 16 --quiet --summary "$R/melt.json"
d=$(deck 30 "$W/run.h5")
echo "bin,threads,rep,collisions,wall_seconds" >"$R/ab.csv"
for rep in $(seq "$REPS"); do
    [ $(( $(date +%s) - t0 )) -gt "$LIMIT" ] && break
    for t in 2 4 16; do
        if [ $((rep % 2)) = 1 ]; then order="old new"; else order="new old"; fi
        for b in $order; do
            cp "$W/melt.h5" "$W/run.h5"
            s=$(NBEP_TEAM=always "$LD" --library-path "$K" "$D/nbep.$b" run "$d" --resume "$W/run.h5" -t "$t" --quiet --summary -) ||
                { echo "failed: $b $t $rep" >>"$R/errors.txt"; continue; }
            echo "$b,$t,$rep,$(echo "$s" | field collisions),$(echo "$s" | field wall_seconds)" >>"$R/ab.csv"
        done
    done
done
echo "$(( $(date +%s) - t0 )) s, $(($(wc -l <"$R/ab.csv") - 1)) rows" >"$R/log.txt"
