#!/usr/bin/env bash
# One thread, pinned or not: nbep with OMP_PLACES=cores OMP_PROC_BIND=close (CPU 0), bound to
# CPU 8, and unbound; EDMD unbound and on CPU 8 (taskset). N = 32000, phi 0.30 and 0.50.
set -u
D=$(cd "$(dirname "$0")" && pwd)
K=$D/../dev/kit/lib
LD=$(echo "$K"/ld-linux*)
R=${OUT:-/tmp/out}
W=/tmp/w2
mkdir -p "$R" "$W"
nb() { "$LD" --library-path "$K" "$D/nbep" "$@"; }
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
command -v taskset >"$R/taskset.txt" 2>&1
tar xJf "$D/inits.tar.xz" -C "$W"
for sc in "32000 0.30 3" "32000 0.50 0.75"; do
    set -- $sc
    nb run "$(deck "$1" "$2" 20 "$W/melt-$1-$2.h5" 20 '"position", "velocity"')" -t 16 --quiet
    for e in "$D"/edmd-"$1"-"$2"-*; do
        rm -rf "$W/${e##*/}" && cp -r "$e" "$W/" && cp "$W/init-$1-$2.sph" "$W/${e##*/}/init.sph"
    done
done
echo "engine,how,n,phi,rep,collisions,seconds" >"$R/pin.csv"
edmd_once() { # dir prefix... -> "collisions seconds"
    local a b dir=$1; shift
    a=$(now)
    (cd "$dir" && "$@" "$LD" --library-path "$K" ./md >run.log 2>&1)
    b=$(now)
    echo "$(sed -n 's/^Simtime: .*Collisions: \([0-9]*\),.*/\1/p' "$dir/run.log" | tail -1) $(awk -v a="$a" -v b="$b" 'BEGIN { print b - a }')"
}
for rep in 1 2 3; do
    for sc in "32000 0.30 3" "32000 0.50 0.75"; do
        set -- $sc
        steps=$(awk -v s="$3" 'BEGIN { printf "%d", 20 + s / 0.05 + 0.5 }')
        d=$(deck "$1" "$2" "$steps" "$W/run.h5" 20)
        for how in cpu0 cpu8 free; do
            cp "$W/melt-$1-$2.h5" "$W/run.h5"
            case $how in
                cpu0) s=$(OMP_PLACES=cores OMP_PROC_BIND=close nb run "$d" --resume "$W/run.h5" -t 1 --quiet --summary -) ;;
                cpu8) s=$(OMP_PLACES="{8}" OMP_PROC_BIND=close nb run "$d" --resume "$W/run.h5" -t 1 --quiet --summary -) ;;
                free) s=$(OMP_PROC_BIND=false nb run "$d" --resume "$W/run.h5" -t 1 --quiet --summary -) ;;
            esac
            echo "nbep,$how,$1,$2,$rep,$(echo "$s" | field collisions),$(echo "$s" | field wall_seconds)" >>"$R/pin.csv"
        done
        T2=$(awk -v s="$3" 'BEGIN { print 0.1 + s }')
        for how in free cpu8; do
            pre=(); [ "$how" = cpu8 ] && pre=(taskset -c 8)
            read -r ca wa < <(edmd_once "$W/edmd-$1-$2-0.1" "${pre[@]}")
            read -r cb wb < <(edmd_once "$W/edmd-$1-$2-$T2" "${pre[@]}")
            [ -n "$ca" ] && [ -n "$cb" ] || continue
            echo "edmd,$how,$1,$2,$rep,$((cb - ca)),$(awk -v a="$wa" -v b="$wb" 'BEGIN { print b - a }')" >>"$R/pin.csv"
        done
    done
done
cat "$R/pin.csv"
