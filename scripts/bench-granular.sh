#!/bin/sh
# Granular benchmark (issue 9): a pile of spheres poured into a box and settling under gravity,
# e = 0.5 against e = 1, on 1 and 2 threads. Prints, per run, the collisions per step and per
# sphere and step, and the wall time, from nbep's JSON summary. Runs are interleaved, repeats
# outermost, and the median of the repeats is reported.
#   scripts/bench-granular.sh [COUNT [STEPS [REPEATS]]]     (default 200 1500 3)
# The deck is written on the fly (a box 0.8 x 0.8 x 3 m, radius 0.05, grid neighbours).
set -eu
count=${1:-200}
steps=${2:-1500}
reps=${3:-3}
nbep=${NBEP:-bin/nbep}
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
cat > "$tmp/pile.deck" <<DECK
run: { algorithm = "predictive"; steps = $steps; dt = 1.0e-3; seed = 1; neighbors = "grid"; };
physics: { gravity = [0.0, 0.0, -9.81]; restitution = 0.5; };
box: { min = [0.0, 0.0, 0.0]; max = [0.8, 0.8, 3.0]; };
spheres = ( { count = $count; radius = 0.05; mass = 1.0; place = "random"; speed = 0.0; } );
output: { file = "pile.h5"; every = $steps; };
DECK
for r in $(seq 1 "$reps"); do
  for e in 0.5 1.0; do
    for t in 1 2; do
      "$nbep" run "$tmp/pile.deck" --quiet -t "$t" --set physics.restitution=$e \
        -o "$tmp/out.h5" --summary "$tmp/s-$e-$t-$r.json"
    done
  done
done
python3 - "$tmp" "$count" "$steps" "$reps" <<'PY'
import json, statistics, sys
tmp, n, steps, reps = sys.argv[1], int(sys.argv[2]), int(sys.argv[3]), int(sys.argv[4])
print(f"pile: {n} spheres, {steps} steps, median of {reps}")
print("e     threads  collisions/step  per sphere/step  wall s  energy_rel_drift")
for e in ("0.5", "1.0"):
    for t in (1, 2):
        runs = [json.load(open(f"{tmp}/s-{e}-{t}-{r}.json")) for r in range(1, reps + 1)]
        c = runs[0]["collisions"] / runs[0]["steps"]
        w = statistics.median(x["wall_seconds"] for x in runs)
        print(f"{e:5} {t:7}  {c:15.1f}  {c / n:15.2f}  {w:6.2f}  {runs[0]['energy_rel_drift']:.3g}")
PY
