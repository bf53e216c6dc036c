#!/usr/bin/env bash
# On a borrowed 16-core node: where the team loop's leader's time goes (bench_leader), with the
# plain build timed in the same session, in turn (plain first in odd repeats, bench_leader
# first in even ones), one thread beside them. Kit: ../dev/kit/lib (scripts/pack-kit.sh).
set -u
D=$(cd "$(dirname "$0")" && pwd)
K=$D/../dev/kit/lib
LD=$(echo "$K"/ld-linux*)
R=${OUT:-/tmp/out}
W=/tmp/w3
REPS=${REPS:-2}
SCENES=${SCENES:-"256000 0.30 0.5;32000 0.50 0.75"}
mkdir -p "$R/leader" "$W"
run() { local b=$1; shift; "$LD" --library-path "$K" "$D/$b" "$@"; }
export OMP_PLACES=cores OMP_PROC_BIND=close
field() { sed -n "s/.*\"$1\": *\([0-9.e+-]*\).*/\1/p"; }
side() { awk -v n="$1" -v p="$2" 'BEGIN { printf "%.12g", (n * atan2(0, -1) / (6 * p)) ^ (1 / 3) }'; }
deck() { # n phi steps file every [fields]
    local d="$W/fluid-$1-$2-$3.deck" L
    L=$(side "$1" "$2")
    cat >"$d" <<E2
run: { algorithm = "predictive"; steps = $3; dt = 0.05; threads = 1; seed = 1; neighbors = "cells"; };
box: { min = [0.0, 0.0, 0.0]; max = [$L, $L, $L]; periodic = [true, true, true]; };
spheres = ( { count = $1; radius = 0.5; mass = 1.0; place = "lattice"; speed = 1.7320508075688772; } );
output: { file = "$4"; every = $5; fields = [${6:-}]; stats = false; };
E2
    echo "$d"
}
{ nproc; grep -m1 "model name" /proc/cpuinfo; run nbep --version; } >"$R/machine.txt" 2>&1
IFS=';' read -r -a scenes <<<"$SCENES"
for sc in "${scenes[@]}"; do
    set -- $sc
    run nbep run "$(deck "$1" "$2" 20 "$W/melt-$1-$2.h5" 20 '"position", "velocity"')" -t 16 --quiet
done
echo "bin,n,phi,threads,rep,collisions,wall_seconds" >"$R/rows.csv"
one() { # bin n phi S threads rep
    local steps d s
    steps=$(awk -v s="$4" 'BEGIN { printf "%d", 20 + s / 0.05 + 0.5 }')
    d=$(deck "$2" "$3" "$steps" "$W/run.h5" 20)
    cp "$W/melt-$2-$3.h5" "$W/run.h5"
    s=$(NBEP_TEAM=always run "$1" run "$d" --resume "$W/run.h5" -t "$5" --quiet --summary - \
        2>"$R/leader/$1-$2-$3-$5-$6.txt")
    echo "$1,$2,$3,$5,$6,$(echo "$s" | field collisions),$(echo "$s" | field wall_seconds)" >>"$R/rows.csv"
}
for rep in $(seq "$REPS"); do
    for sc in "${scenes[@]}"; do
        set -- $sc
        one nbep "$1" "$2" "$3" 1 "$rep"
        for t in 4 16; do
            if [ $((rep % 2)) = 1 ]; then order="nbep bench_leader"; else order="bench_leader nbep"; fi
            for b in $order; do one "$b" "$1" "$2" "$3" "$t" "$rep"; done
        done
    done
done
tar czf "$R/all.tgz" -C "$R" rows.csv machine.txt leader
cat "$R/rows.csv"
rm -rf "$R/leader" "$R/rows.csv" "$R/machine.txt"
