#!/bin/sh
# Hopper benchmark: inputs/hopper.deck (spheres dropped into an open V-groove of two planes,
# e = 0.5, no box) with COUNT spheres in a region that grows with COUNT (the deck's 40 fill
# 0.8 x 1 x 0.5 m; COUNT of them fill a region as long in y as it takes to keep that density),
# in run.neighbors = "grid" and "cells" (cells without a box: its cells cover the spheres'
# extent, laid out afresh whenever they leave it), on 1 and 2 threads, side by side in one
# run: repeats outermost, every configuration once per repeat, the median wall time of the
# repeats reported with the collisions (the same in every repeat: runs are deterministic).
#   scripts/bench-hopper.sh [COUNT [STEPS [REPEATS]]]     (default 400 1000 3)
# The two modes reach the same physics by different roundings, so their collision counts
# differ a little (a chaotic, dissipative pile); compare collisions per second as well as time.
set -eu
# --help, and the arguments' check (scripts/bench-count-args.sh)
. "$(dirname "$0")/bench-count-args.sh"
bench_count_args "$0" "$@"
count=${1:-400}
steps=${2:-1000}
reps=${3:-3}
modes=${MODES:-grid cells}
nbep=${NBEP:-bin/nbep}
py=/usr/bin/python3
len=$(awk -v n="$count" 'BEGIN { printf "%.4f", n / 40.0 }')
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
for r in $(seq 1 "$reps"); do
  for nb in $modes; do
    for t in 1 2; do
      "$nbep" run inputs/hopper.deck --quiet -t "$t" -n "$steps" \
        --set spheres.[0].count="$count" --set "spheres.[0].region.max=[0.4, $len, 1.0]" \
        --set run.neighbors="\"$nb\"" --set output.every="$steps" \
        -o "$tmp/$nb-$t.h5" --summary "$tmp/s-$nb-$t-$r.json"
    done
  done
done
"$py" - "$tmp" "$count" "$steps" "$reps" "$modes" <<'PY'
import json, statistics, sys
tmp, n, steps, reps = sys.argv[1], int(sys.argv[2]), int(sys.argv[3]), int(sys.argv[4])
print(f"hopper: {n} spheres, {steps} steps, median wall time of {reps} (spread)")
print("| neighbors | threads | collisions | wall s | collisions/s | energy drift | max overlap (radii) |")
print("| --- | --- | --- | --- | --- | --- | --- |")
for nb in sys.argv[5].split():
    for t in (1, 2):
        runs = [json.load(open(f"{tmp}/s-{nb}-{t}-{r}.json")) for r in range(1, reps + 1)]
        w = [x["wall_seconds"] for x in runs]
        m = statistics.median(w)
        c = runs[0]["collisions"]
        print(f"| {nb} | {t} | {c} | {m:.2f} ({min(w):.2f}-{max(w):.2f}) | {c / m / 1e3:.0f} k | "
              f"{runs[0]['energy_rel_drift']:.3g} | {runs[0]['max_overlap_rel']:.2g} |")
PY
