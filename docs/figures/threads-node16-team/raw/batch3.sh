#!/bin/bash
# Batch 3 (the node quiet, up 7 min): the large fluid again, 3 repeats; rows in batch3-rows.csv.
# Before it, the all-pairs runs of allpairs.txt (the same loop over "4 8 12 16", n = 16384).
K=devkit; export OMP_PLACES=cores OMP_PROC_BIND=close
$K/nbep run $K/bd256/fluid-256000-0.30-20-1.deck -t 16 --quiet --summary - | tr ',' '\n' | grep '"collisions"'
sed "s#file = \"[^\"]*\"#file = \"/tmp/r.h5\"#" $K/bd256/fluid-256000-0.30-40-1.deck > /tmp/d.deck
for i in 1 2 3; do for c in "1 auto" "4 always" "8 always" "16 always" "16 auto"; do
    set -- $c; cp $K/bd256/melt-256000-0.30.h5 /tmp/r.h5
    s=$(NBEP_TEAM=$2 $K/nbep run /tmp/d.deck -t $1 --resume /tmp/r.h5 --quiet --summary -)
    echo "$i $c $(echo "$s" | tr ',' '\n' | grep -E 'wall_seconds|"collisions"' | tr '\n' ' ')"
done; done
