#!/bin/bash
# On the 16-core device: thread scaling of the granular pour (grid mode: the horizon seeds the
# pair search, and each step's rounds run on the crew the run finds fastest; NBEP_TEAM=always:
# every thread, as before), of the hopper and of the paper's box in grid mode, beside cells
# mode's one thread.
# Repeats outermost, thread counts interleaved. Rows to $OUT/rows.csv.
set -u
K=devkit
O=${OUT:-/tmp/devout}; mkdir -p "$O"
exec > >(tee -a "$O/log.txt") 2>&1
T0=$(date +%s); LIMIT=${LIMIT:-400}
el() { echo "$(( $(date +%s) - T0 ))"; }
late() { [ "$(el)" -ge "$LIMIT" ]; }
nproc; (lscpu 2>/dev/null | grep -E "Model name|Socket|Core|L2|L3") ; "$K/nbep" --version || exit 1
export OMP_PLACES=cores OMP_PROC_BIND=close
f() { sed -n "s/.*\"$1\": *\([0-9.e+-]*\).*/\1/p"; }
echo "scene,neighbors,threads,rep,collisions,wall_seconds,energy_drift" >"$O/rows.csv"
side=$(awk 'BEGIN { printf "%.4f", sqrt(300 / 2000.0) }')
pour() { # count steps neighbors threads rep [side]   (TEAM: NBEP_TEAM)
    local s extra=()
    [ -n "${6:-}" ] && extra=(--set "spheres.[0].count=$1" --set "box.max=[$6, $6, 1.2]")
    s=$(NBEP_TEAM=${TEAM:-} "$K/nbep" run inputs/pile.deck --quiet -t "$4" -n "$2" --set physics.restitution=0.5 \
        --set "run.neighbors=\"$3\"" --set output.every="$2" "${extra[@]}" \
        -o /tmp/pour.h5 --summary -) || { echo "failed pour $*"; return; }
    echo "pile$1-$2${TEAM:+-$TEAM},$3,$4,$5,$(echo "$s" | f collisions),$(echo "$s" | f wall_seconds),$(echo "$s" | f energy_rel_drift)" | tee -a "$O/rows.csv"
}
box() { # neighbors threads rep
    local s
    s=$(NBEP_TEAM=${TEAM:-} "$K/nbep" run inputs/paper-box.deck --quiet -t "$2" -n 100 --set spheres.[0].count=32768 \
        --set "run.neighbors=\"$1\"" --set output.every=100 -o /tmp/box.h5 --summary -) || { echo "failed box $*"; return; }
    echo "box32768${TEAM:+-$TEAM},$1,$2,$3,$(echo "$s" | f collisions),$(echo "$s" | f wall_seconds),$(echo "$s" | f energy_rel_drift)" | tee -a "$O/rows.csv"
}
hopper() { # threads rep
    local s
    s=$(NBEP_TEAM=${TEAM:-} "$K/nbep" run inputs/hopper.deck --quiet -t "$1" -o /tmp/hop.h5 --summary -) || { echo "failed hopper $*"; return; }
    echo "hopper${TEAM:+-$TEAM},grid,$1,$2,$(echo "$s" | f collisions),$(echo "$s" | f wall_seconds),$(echo "$s" | f energy_rel_drift)" | tee -a "$O/rows.csv"
}
for rep in 1 2 3; do
    for t in 1 16; do late || pour 300 450 grid "$t" "$rep" "$side"; done
    TEAM=always; late || pour 300 450 grid 16 "$rep" "$side"; TEAM=
    for t in 1 16; do late || box grid "$t" "$rep"; done
    TEAM=always; late || box grid 16 "$rep"; TEAM=
    for t in 1 16; do late || hopper "$t" "$rep"; done
    TEAM=always; late || hopper 16 "$rep"; TEAM=
done
echo "[$(el) s] done"
