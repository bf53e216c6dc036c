#!/bin/bash
# On the 16-core device (2026-11-27, commit 24f22ee): thread scaling of the team of up to 16
# on the dense fluids, beside EDMD Single (1 core), repeats as the outer loop, everything
# interleaved. Rows to $OUT/rows.csv as they come; log to $OUT/log.txt.
set -u
K=devkit
O=${OUT:-/tmp/devout}; mkdir -p "$O"
exec > >(tee -a "$O/log.txt") 2>&1
T0=$(date +%s); LIMIT=${LIMIT:-350}
el() { echo "$(( $(date +%s) - T0 ))"; }
late() { [ "$(el)" -ge "$LIMIT" ]; }
LD=$K/lib/ld-linux-x86-64.so.2
echo "[$(el) s] machine"
nproc; (lscpu 2>/dev/null | grep -E "Model name|Socket|Core|Thread|NUMA|L2|L3|MHz") ; free -g | head -2; uname -r
command -v cc || echo "no cc"; [ -x /usr/bin/time ] && echo "GNU time: yes" || echo "GNU time: no"
"$K/nbep" --version || exit 1
export OMP_PLACES=cores OMP_PROC_BIND=close
gunzip -k "$K/bd256/init-256000-0.30.sph.gz" 2>/dev/null ||
    python3 -c 'import gzip,shutil,sys; shutil.copyfileobj(gzip.open(sys.argv[1]), open(sys.argv[1][:-3], "wb"))' "$K/bd256/init-256000-0.30.sph.gz"
ls -la "$K/bd256/"
HO() { "$LD" --library-path "$K/lib" "$K/bd32/handover" 2>/dev/null || echo "-"; }
echo "[$(el) s] handover ns: $(HO)"
f() { sed -n "s/.*\"$1\": *\([0-9.e+-]*\).*/\1/p"; }
echo "[$(el) s] melts (expect 157293, 1182547, 1265699 collisions)"
for d in $K/bd32/fluid-32000-0.30-20-1.deck $K/bd32/fluid-32000-0.50-20-1.deck $K/bd256/fluid-256000-0.30-20-1.deck; do
    s=$("$K/nbep" run "$d" -t "${MT:-16}" --quiet --summary -) || { echo "melt failed: $d"; exit 1; }
    echo "$d $(echo "$s" | f collisions) wall $(echo "$s" | f wall_seconds)"
done
echo "scene,engine,threads,team,rep,collisions,wall_seconds,setup_seconds,rss_bytes,handover_ns" >"$O/rows.csv"
nb() { # scene melt deck run.h5 threads team rep
    local s
    cp "$2" "$4"
    s=$(NBEP_TEAM=$6 "$K/nbep" run "$3" -t "$5" --resume "$4" --quiet --summary -) || { echo "nbep failed $*"; return; }
    echo "$1,nbep,$5,$6,$7,$(echo "$s" | f collisions),$(echo "$s" | f wall_seconds),$(echo "$s" | f setup_seconds),$(echo "$s" | f peak_rss_bytes)," | tee -a "$O/rows.csv"
}
ed_once() { # dir -> collisions seconds
    local t0 t1 c
    t0=$(date +%s.%N); (cd "$1" && "../../lib/ld-linux-x86-64.so.2" --library-path ../../lib ./md >run.log 2>&1); t1=$(date +%s.%N)
    c=$(sed -n 's/^Simtime: .*Collisions: \([0-9]*\),.*/\1/p' "$1/run.log" | tail -1)
    echo "$c $(awk -v a="$t0" -v b="$t1" 'BEGIN { print b - a }')"
}
ed() { # scene dirA dirB rep
    local ca wa cb wb
    read -r ca wa < <(ed_once "$2"); read -r cb wb < <(ed_once "$3")
    echo "$1,edmd,1,-,$4,$((cb - ca)),$(awk -v a="$wa" -v b="$wb" 'BEGIN { print b - a }'),,," | tee -a "$O/rows.csv"
}
round() { # scene dir n phi runsteps edmdB rep
    local m=$2/melt-$3-$4.h5 d=$2/fluid-$3-$4-$5-1.deck r=/tmp/run-$3-$4.h5 c
    sed "s#file = \"[^\"]*\"#file = \"$r\"#" "$d" >/tmp/deck-$3-$4.deck
    echo "$1,probe,,,$7,,,,,$(HO)" >>"$O/rows.csv"
    for c in "${CONFIGS[@]}"; do
        late && { echo "[$(el) s] deadline: skip $1 rep $7 $c"; return; }
        nb "$1" "$m" /tmp/deck-$3-$4.deck "$r" ${c% *} "${c#* }" "$7"
        [ "${c#* }" = auto ] && [ "${c% *}" = 1 ] && { late || ed "$1" "$2/edmd-$3-$4-0.1" "$2/edmd-$3-$4-$6" "$7"; }
    done
}
# NBEP_TEAM=auto: a value nbep does not know, read as unset (the chooser)
if [ -n "${LOCAL:-}" ]; then CONFIGS=("1 auto" "2 auto" "2 always"); else
CONFIGS=("1 auto" "2 auto" "4 auto" "8 auto" "16 auto" "4 always" "8 always" "16 always" "16 8"); fi
for rep in 1 2 3; do
    echo "[$(el) s] rep $rep"
    round f256-30 $K/bd256 256000 0.30 40 1.1 "$rep"
    round f32-30 $K/bd32 32000 0.30 80 3.1 "$rep"
    round f32-50 $K/bd32 32000 0.50 35 0.85 "$rep"
done
echo "[$(el) s] done"
