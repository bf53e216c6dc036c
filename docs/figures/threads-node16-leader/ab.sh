#!/usr/bin/env bash
# On a borrowed 16-core node: the team loop before (old: 8d57897) and after (new) its places'
# counts were left to their handlers, on the dense fluids of make bench-dense, 1 to 16 threads,
# interleaved; then where the leader's time goes (bench_leader) and a task farm (16 one-thread
# runs at once against one alone). It ran from a folder holding kit/lib (scripts/pack-kit.sh's
# libraries and loader), nbep.old and nbep.new (bin/nbep at 8d57897 and 1632905), bench_leader
# (make build/bench/bench_leader) and handover (scripts/handover.c), carried to the node:
#   bash DIR/ab.sh                 everything (rows.csv, leader-*.txt, farm.csv)
#   MAIN_ONLY=1 bash DIR/ab.sh     the fluids' rows only
# rows.csv, machine.txt and handover.txt here are from a MAIN_ONLY run (the first run's rows did
# not come back from the node); raw/ holds the first run's leader-*.txt and farm.csv.
set -u
D=$(cd "$(dirname "$0")" && pwd)
LD=$(echo "$D"/kit/lib/ld-linux*)
R=${OUT:-/tmp/out}
W=/tmp/w
SCENES=${SCENES:-"256000 0.30 0.5;32000 0.30 3;32000 0.50 0.75"}
THREADS=${THREADS:-"1 2 4 8 16"}
REPS=${REPS:-3}
FARM=${FARM:-16}
mkdir -p "$R" "$W"; rm -f "$R/errors.txt" "$R/log.txt"
nb() { local b=$1; shift; "$LD" --library-path "$D/kit/lib" "$D/$b" "$@"; }
export OMP_PLACES=cores OMP_PROC_BIND=close
field() { sed -n "s/.*\"$1\": *\([0-9.e+-]*\).*/\1/p"; }
side() { awk -v n="$1" -v p="$2" 'BEGIN { printf "%.12g", (n * atan2(0, -1) / (6 * p)) ^ (1 / 3) }'; }
deck() { # n phi steps file every [fields] -> deck path
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
{ nproc; grep -m1 "model name" /proc/cpuinfo; nb nbep.old --version; nb nbep.new --version; } >"$R/machine.txt" 2>&1
"$LD" --library-path "$D/kit/lib" "$D/handover" 5 >"$R/handover.txt" 2>&1
"$LD" --library-path "$D/kit/lib" "$D/handover" --from 0 3 >>"$R/handover.txt" 2>&1
echo "bin,n,phi,threads,team,rep,collisions,wall_seconds,setup_seconds,peak_rss_bytes" >"$R/rows.csv"
t0=$(date +%s)
IFS=';' read -r -a scenes <<<"$SCENES"
for sc in "${scenes[@]}"; do
    set -- $sc
    d=$(deck "$1" "$2" 20 "$W/melt-$1-$2.h5" 20 '"position", "velocity"')
    nb nbep.new run "$d" -t 16 --quiet || echo "melt failed: $sc" >>"$R/errors.txt"
done
echo "melts: $(( $(date +%s) - t0 )) s" >>"$R/log.txt"
one() { # bin n phi S threads team rep
    local steps d s
    steps=$(awk -v s="$4" 'BEGIN { printf "%d", 20 + s / 0.05 + 0.5 }')
    d=$(deck "$2" "$3" "$steps" "$W/run.h5" 20)
    cp "$W/melt-$2-$3.h5" "$W/run.h5"
    if [ "$6" = own ]; then
        s=$(nb "$1" run "$d" --resume "$W/run.h5" -t "$5" --quiet --summary -)
    else
        s=$(NBEP_TEAM=$6 nb "$1" run "$d" --resume "$W/run.h5" -t "$5" --quiet --summary -)
    fi || { echo "failed: $*" >>"$R/errors.txt"; return; }
    echo "$1,$2,$3,$5,$6,$7,$(echo "$s" | field collisions),$(echo "$s" | field wall_seconds),$(echo "$s" | field setup_seconds),$(echo "$s" | field peak_rss_bytes)" >>"$R/rows.csv"
}
for rep in $(seq "$REPS"); do
    for sc in "${scenes[@]}"; do
        set -- $sc
        for t in $THREADS; do
            team=always; [ "$t" = 1 ] && team=own
            for b in nbep.old nbep.new; do one "$b" "$1" "$2" "$3" "$t" "$team" "$rep"; done
        done
        for b in nbep.old nbep.new; do one "$b" "$1" "$2" "$3" "${t}" own "$rep"; done
    done
    echo "rep $rep: $(( $(date +%s) - t0 )) s" >>"$R/log.txt"
done
[ -n "${MAIN_ONLY:-}" ] && { tar czf "$R/all.tgz" -C "$R" rows.csv log.txt machine.txt handover.txt; exit 0; }
# where the leader's time goes (tests/bench/bench_leader.c), the large fluid and the dense one
for sc in "256000 0.30 0.5" "32000 0.50 0.75"; do
    set -- $sc
    [ -f "$W/melt-$1-$2.h5" ] || continue
    for t in 2 4 16; do
        steps=$(awk -v s="$3" 'BEGIN { printf "%d", 20 + s / 0.05 + 0.5 }')
        d=$(deck "$1" "$2" "$steps" "$W/run.h5" 20)
        cp "$W/melt-$1-$2.h5" "$W/run.h5"
        NBEP_TEAM=always nb bench_leader run "$d" --resume "$W/run.h5" -t "$t" --quiet --summary - \
            >"$R/leader-$1-$2-$t.txt" 2>&1
    done
done
echo "leader: $(( $(date +%s) - t0 )) s" >>"$R/log.txt"
# a task farm: 16 one-thread runs of the N = 32000, phi = 0.30 fluid at once, against one alone
farm() { # k
    local d steps=60 i
    d=$(deck 32000 0.30 "$steps" "$W/farm-X.h5" 20)
    [ -f "$W/melt-32000-0.30.h5" ] || return
    for i in $(seq "$1"); do
        cp "$W/melt-32000-0.30.h5" "$W/farm-$i.h5"
        sed "s|farm-X|farm-$i|" "$d" >"$W/farm-$i.deck"
    done
    for i in $(seq "$1"); do
        (s=$(OMP_PLACES="{$((i - 1))}" nb nbep.new run "$W/farm-$i.deck" --resume "$W/farm-$i.h5" -t 1 --quiet --summary -)
            echo "farm$1,$i,$(echo "$s" | field collisions),$(echo "$s" | field wall_seconds)" >>"$R/farm.csv") &
    done
    wait
}
echo "kind,i,collisions,wall_seconds" >"$R/farm.csv"
for rep in 1 2; do farm 1; farm "$FARM"; farm 1; done
echo "farm: $(( $(date +%s) - t0 )) s" >>"$R/log.txt"
