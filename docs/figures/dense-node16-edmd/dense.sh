#!/usr/bin/env bash
# On a borrowed 16-core node: nbep (1, 2, 4 and 16 threads, the run's own choice of way) beside
# EDMD Single (one core) on the dense fluids of make bench-dense, interleaved, 3 repeats. The
# fluid is nbep's melt at T1 = 1 (melted here, the same bits as anywhere); EDMD starts from its
# positions (init.sph, written where the melt was made, as scripts/bench-dense.sh does) and is
# timed as the difference of two runs, to 0.1 and to 0.1 + S. Everything runs through the kit's
# loader and libraries (../dev/kit/lib, scripts/pack-kit.sh).
set -u
D=$(cd "$(dirname "$0")" && pwd)
K=$D/../dev/kit/lib
LD=$(echo "$K"/ld-linux*)
R=${OUT:-/tmp/out}
W=/tmp/w2
REPS=${REPS:-3}
SCENES=${SCENES:-"256000 0.30 0.5;32000 0.30 3;32000 0.50 0.75"}
THREADS=${THREADS:-"1 2 4 16"}
mkdir -p "$R" "$W"
nb() { "$LD" --library-path "$K" "$D/nbep" "$@"; }
export OMP_PLACES=cores OMP_PROC_BIND=close
field() { sed -n "s/.*\"$1\": *\([0-9.e+-]*\).*/\1/p"; }
side() { awk -v n="$1" -v p="$2" 'BEGIN { printf "%.12g", (n * atan2(0, -1) / (6 * p)) ^ (1 / 3) }'; }
now() { date +%s.%N; }
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
{ nproc; grep -m1 "model name" /proc/cpuinfo; nb --version; } >"$R/machine.txt" 2>&1
tar xJf "$D/inits.tar.xz" -C "$W"
IFS=';' read -r -a scenes <<<"$SCENES"
t0=$(date +%s)
for sc in "${scenes[@]}"; do
    set -- $sc
    nb run "$(deck "$1" "$2" 20 "$W/melt-$1-$2.h5" 20 '"position", "velocity"')" -t 16 --quiet ||
        echo "melt failed: $sc" >>"$R/errors.txt"
    for e in "$D"/edmd-"$1"-"$2"-*; do
        rm -rf "$W/${e##*/}" && cp -r "$e" "$W/" && cp "$W/init-$1-$2.sph" "$W/${e##*/}/init.sph"
    done
done
echo "melts: $(( $(date +%s) - t0 )) s" >>"$R/log.txt"
echo "engine,n,phi,threads,rep,collisions,seconds,rss_bytes" >"$R/rows.csv"
edmd_once() { # dir -> "collisions seconds"
    local a b
    a=$(now)
    (cd "$1" && "$LD" --library-path "$K" ./md >run.log 2>&1)
    b=$(now)
    echo "$(sed -n 's/^Simtime: .*Collisions: \([0-9]*\),.*/\1/p' "$1/run.log" | tail -1) $(awk -v a="$a" -v b="$b" 'BEGIN { print b - a }')"
}
for rep in $(seq "$REPS"); do
    for sc in "${scenes[@]}"; do
        set -- $sc
        steps=$(awk -v s="$3" 'BEGIN { printf "%d", 20 + s / 0.05 + 0.5 }')
        d=$(deck "$1" "$2" "$steps" "$W/run.h5" 20)
        for t in $THREADS; do
            cp "$W/melt-$1-$2.h5" "$W/run.h5"
            s=$(nb run "$d" --resume "$W/run.h5" -t "$t" --quiet --summary -) ||
                { echo "nbep failed: $sc $t" >>"$R/errors.txt"; continue; }
            echo "nbep,$1,$2,$t,$rep,$(echo "$s" | field collisions),$(echo "$s" | field wall_seconds),$(echo "$s" | field peak_rss_bytes)" >>"$R/rows.csv"
        done
        T2=$(awk -v s="$3" 'BEGIN { print 0.1 + s }')
        read -r ca wa < <(edmd_once "$W/edmd-$1-$2-0.1")
        read -r cb wb < <(edmd_once "$W/edmd-$1-$2-$T2")
        echo "edmd,$1,$2,1,$rep,$((cb - ca)),$(awk -v a="$wa" -v b="$wb" 'BEGIN { print b - a }')," >>"$R/rows.csv"
    done
    echo "rep $rep: $(( $(date +%s) - t0 )) s" >>"$R/log.txt"
done
tar czf "$R/all.tgz" -C "$R" rows.csv log.txt machine.txt $( [ -f "$R/errors.txt" ] && echo errors.txt)
cat "$R/rows.csv"
