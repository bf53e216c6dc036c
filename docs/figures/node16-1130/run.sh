#!/usr/bin/env bash
# On a borrowed 16-core node, from build/dev (prep.sh): nbep on 1, 2, 4, 8 and 16 threads (the
# run's own choice of way, and NBEP_TEAM=always, the whole team at every step) beside EDMD
# Single (one core) on the dense fluids of make bench-dense, interleaved within each repeat;
# then the paper's box in its three predictive modes. Each fluid is nbep's melt at T1 = 1
# (melted here, the same bits as anywhere), resumed for the stretch of bench-dense at
# SCALE = 0.125 (N = 256000) or 0.25 (N = 32000); EDMD starts from the melt's positions and is
# timed as the difference of two runs, to 0.1 and to 0.1 + S. Threads pinned. Rows in
# $OUT/rows.csv and $OUT/paper.csv (nbep's collisions less the melt's: a resumed summary counts
# from step 0 since 2026-11-30). No repeat starts after LIMIT seconds (default 300). At
# 2026-11-30's HEAD, a copy of node16-e053a30/run.sh with that change and the melt's fields kept.
set -u
cd "$(dirname "$0")/../../.." || exit 1
D=$PWD/build/dev
K=$D/kit/lib
LD=$(echo "$K"/ld-linux*)
R=${OUT:-/tmp/out}
W=/tmp/w
REPS=${REPS:-3}
LIMIT=${LIMIT:-300}
SCENES=${SCENES:-"256000 0.30 0.5;32000 0.30 3;32000 0.50 0.75"}
THREADS=${THREADS:-"2 4 8 16"}
mkdir -p "$R" "$W"
nb() { "$LD" --library-path "$K" "$D/kit/nbep.bin" "$@"; }
export OMP_PLACES=cores OMP_PROC_BIND=close
field() { sed -n "s/.*\"$1\": *\([0-9.e+-]*\).*/\1/p"; }
side() { awk -v n="$1" -v p="$2" 'BEGIN { printf "%.12g", (n * atan2(0, -1) / (6 * p)) ^ (1 / 3) }'; }
now() { date +%s.%N; }
t0=$(date +%s)
el() { echo $(( $(date +%s) - t0 )); }
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
{ nproc; lscpu; nb --version; } >"$R/machine.txt" 2>&1
"$LD" --library-path "$K" "$D/handover" --from 0 3 >"$R/handover.txt" 2>&1
tar xJf "$D/inits.tar.xz" -C "$W"
IFS=';' read -r -a scenes <<<"$SCENES"
for sc in "${scenes[@]}"; do
    set -- $sc
    nb run "$(deck "$1" "$2" 20 "$W/melt-$1-$2.h5" 20 '"position", "velocity"')" -t 16 --quiet --summary "$R/melt-$1-$2.json" ||
        echo "melt failed: $sc" >>"$R/errors.txt"
    for e in "$D"/edmd-"$1"-"$2"-*; do
        rm -rf "$W/${e##*/}" && cp -r "$e" "$W/" && cp "$W/init-$1-$2.sph" "$W/${e##*/}/init.sph"
    done
done
echo "melts: $(el) s" >>"$R/log.txt"
echo "engine,n,phi,threads,team,rep,collisions,seconds,rss_bytes" >"$R/rows.csv"
edmd_once() { # dir -> "collisions seconds"
    local a b
    a=$(now)
    (cd "$1" && "$LD" --library-path "$K" ./md >run.log 2>&1)
    b=$(now)
    echo "$(sed -n 's/^Simtime: .*Collisions: \([0-9]*\),.*/\1/p' "$1/run.log" | tail -1) $(awk -v a="$a" -v b="$b" 'BEGIN { print b - a }')"
}
one() { # n phi deck threads team rep
    cp "$W/melt-$1-$2.h5" "$W/run.h5"
    local s
    s=$(NBEP_TEAM=$5 nb run "$3" --resume "$W/run.h5" -t "$4" --quiet --summary -) ||
        { echo "nbep failed: $*" >>"$R/errors.txt"; return; }
    # a resumed run's summary counts from step 0 (since 2026-11-30): the melt's taken off
    local m
    m=$(field collisions <"$R/melt-$1-$2.json")
    echo "nbep,$1,$2,$4,$5,$6,$(( $(echo "$s" | field collisions) - m )),$(echo "$s" | field wall_seconds),$(echo "$s" | field peak_rss_bytes)" >>"$R/rows.csv"
}
for rep in $(seq "$REPS"); do
    [ "$(el)" -gt "$LIMIT" ] && { echo "rep $rep skipped at $(el) s" >>"$R/log.txt"; break; }
    for sc in "${scenes[@]}"; do
        set -- $sc
        steps=$(awk -v s="$3" 'BEGIN { printf "%d", 20 + s / 0.05 + 0.5 }')
        d=$(deck "$1" "$2" "$steps" "$W/run.h5" 20 '"position", "velocity"')
        one "$1" "$2" "$d" 1 own "$rep"
        for t in $THREADS; do
            one "$1" "$2" "$d" "$t" own "$rep"
            one "$1" "$2" "$d" "$t" always "$rep"
        done
        T2=$(awk -v s="$3" 'BEGIN { print 0.1 + s }')
        read -r ca wa < <(edmd_once "$W/edmd-$1-$2-0.1")
        read -r cb wb < <(edmd_once "$W/edmd-$1-$2-$T2")
        echo "edmd,$1,$2,1,,$rep,$((cb - ca)),$(awk -v a="$wa" -v b="$wb" 'BEGIN { print b - a }')," >>"$R/rows.csv"
    done
    echo "rep $rep: $(el) s" >>"$R/log.txt"
done
# the paper's box (inputs/paper-box.deck: n spheres of radius 0.05 in the 10 m box, gravity,
# e = 1, 100 steps of 1 ms, no per-sphere output), as scripts/bench-threads.sh runs it
echo "mode,n,threads,rep,wall_seconds,setup_seconds,collisions" >"$R/paper.csv"
paper() { # mode n threads rep
    local s
    s=$(nb run inputs/paper-box.deck -n 100 -t "$3" -o "$W/paper.h5" --quiet --summary - \
        --set "spheres.[0].count=$2" --set "run.neighbors=\"$1\"" --set output.every=100 \
        --set 'output.fields=[]' --set output.stats=false) || { echo "paper failed: $*" >>"$R/errors.txt"; return; }
    echo "$1,$2,$3,$4,$(echo "$s" | field wall_seconds),$(echo "$s" | field setup_seconds),$(echo "$s" | field collisions)" >>"$R/paper.csv"
}
for rep in 1 2; do
    for t in 1 $THREADS; do
        paper grid 32768 "$t" "$rep"
        paper cells 32768 "$t" "$rep"
        [ "$rep" = 1 ] && [ "$(el)" -lt $((LIMIT + 120)) ] && paper all 16384 "$t" 1
    done
done
echo "paper: $(el) s" >>"$R/log.txt"
cat "$R/log.txt" "$R/rows.csv" "$R/paper.csv"
