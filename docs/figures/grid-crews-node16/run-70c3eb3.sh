#!/bin/bash
K=devkit; LD=$K/lib/ld-linux-x86-64.so.2
export OMP_PLACES=cores OMP_PROC_BIND=close
"$LD" --library-path "$K/lib" "$K/nbep.dbg" --version
side=$(awk 'BEGIN { printf "%.4f", sqrt(300 / 2000.0) }')
w() { sed -n 's/.*"wall_seconds": *\([0-9.e+-]*\).*/\1/p' /tmp/s.json; }
ways() { awk '$1=="full" {n[$2]++} END {for (w in n) printf "%s:%d ", w, n[w]}' "$1"; }
for r in 1 2 3; do
  for c in "1 " "16 " "16 always"; do
    set -- $c; t=$1; tm=${2:-}
    NBEP_TEAM=$tm XDBG=1 "$LD" --library-path "$K/lib" "$K/nbep.dbg" run inputs/paper-box.deck --quiet -t $t -n 100 --set spheres.[0].count=32768 --set 'run.neighbors="grid"' --set output.every=100 -o /tmp/box.h5 --summary /tmp/s.json > /tmp/x.txt
    echo "box,$t,${tm:-auto},$r,$(w),$(ways /tmp/x.txt)" | tee -a "$OUT/rows.csv"
    NBEP_TEAM=$tm XDBG=1 "$LD" --library-path "$K/lib" "$K/nbep.dbg" run inputs/pile.deck --quiet -t $t -n 450 --set physics.restitution=0.5 --set 'run.neighbors="grid"' --set output.every=450 --set spheres.[0].count=300 --set "box.max=[$side, $side, 1.2]" -o /tmp/pour.h5 --summary /tmp/s.json > /tmp/x.txt
    echo "pour,$t,${tm:-auto},$r,$(w),$(ways /tmp/x.txt)" | tee -a "$OUT/rows.csv"
    NBEP_TEAM=$tm XDBG=1 "$LD" --library-path "$K/lib" "$K/nbep.dbg" run inputs/hopper.deck --quiet -t $t -o /tmp/hop.h5 --summary /tmp/s.json > /tmp/x.txt
    echo "hopper,$t,${tm:-auto},$r,$(w),$(ways /tmp/x.txt)" | tee -a "$OUT/rows.csv"
  done
done
