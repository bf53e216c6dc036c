#!/bin/sh
# Granular benchmark (issue 9): inputs/pile.deck (spheres poured into a box under gravity),
# e = 0.5 against e = 1, on 1 and 2 threads, with run.neighbors = "grid" and "cells", side by
# side in one run. Prints, per configuration, the collisions per step and per sphere and step
# (over the whole run and over its last tenth), the wall time and the energy drift, from
# nbep's JSON summary and /stats. Runs are interleaved, repeats outermost; the median wall time
# of the repeats is reported (counts are the same in every repeat: runs are deterministic).
#   scripts/bench-granular.sh [COUNT [STEPS [REPEATS]]]     (default 300 450 3)
# COUNT spheres replace the deck's 2000 (same radius and height; the floor shrinks with COUNT so
# the pile is as deep as the deck's); the whole deck, settled, is scripts/bench-pile.py. MODES
# (default "grid cells") picks the neighbour modes: MODES=cells scripts/bench-granular.sh 300
# 2000 1 runs the 300-sphere pour until it has settled (about 1.6 s) in some minutes per run;
# grid mode takes several times longer. The table also gives the spheres held at the end
# (velocity exactly zero) and the last step with a collision.
set -eu
# --help, and the arguments' check (scripts/bench-count-args.sh)
. "$(dirname "$0")/bench-count-args.sh"
bench_count_args "$0" "$@"
count=${1:-300}
steps=${2:-450}
reps=${3:-3}
modes=${MODES:-grid cells}
nbep=${NBEP:-bin/nbep}
py=/usr/bin/python3
side=$(awk -v n="$count" 'BEGIN { printf "%.4f", sqrt(n / 2000.0) }')
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
for r in $(seq 1 "$reps"); do
  for nb in $modes; do
    for e in 0.5 1.0; do
      for t in 1 2; do
        "$nbep" run inputs/pile.deck --quiet -t "$t" -n "$steps" \
          --set spheres.[0].count="$count" --set physics.restitution=$e \
          --set run.neighbors="\"$nb\"" --set output.every="$steps" \
          --set box.max="[$side, $side, 1.2]" \
          -o "$tmp/$nb-$e-$t.h5" --summary "$tmp/s-$nb-$e-$t-$r.json"
      done
    done
  done
done
"$py" - "$tmp" "$count" "$steps" "$reps" "$modes" <<'PY'
import json, statistics, sys
import h5py
import numpy as np
tmp, n, steps, reps = sys.argv[1], int(sys.argv[2]), int(sys.argv[3]), int(sys.argv[4])
print(f"pile: {n} spheres, {steps} steps, median wall time of {reps}")
print("| neighbors | e | threads | collisions/step | per sphere/step | last tenth, per sphere/step | held at end | last collision step | wall s | energy drift |")
print("| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |")
for nb in sys.argv[5].split():
    for e in ("0.5", "1.0"):
        for t in (1, 2):
            runs = [json.load(open(f"{tmp}/s-{nb}-{e}-{t}-{r}.json")) for r in range(1, reps + 1)]
            c = runs[0]["collisions"] / runs[0]["steps"]
            f = h5py.File(f"{tmp}/{nb}-{e}-{t}.h5", "r")
            col = f["/stats/collisions"][:]
            tail = col[-max(1, len(col) // 10):].mean()
            held = int((np.abs(f["/frames/velocity"][-1]).sum(axis=1) == 0.0).sum())
            hit = np.nonzero(col)[0]
            last = int(hit[-1]) + 1 if len(hit) else 0
            w = statistics.median(x["wall_seconds"] for x in runs)
            print(f"| {nb} | {e} | {t} | {c:.1f} | {c / n:.3f} | {tail / n:.3f} | {held} | {last} | {w:.2f} | "
                  f"{runs[0]['energy_rel_drift']:.3g} |")
PY
