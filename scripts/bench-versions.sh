#!/usr/bin/env bash
# What the optimistic slab scheme's own bookkeeping would cost a thread per event
# (docs/optimistic-design.md, step 2; tests/bench/bench_versions.c says what it does): one
# binary run without and with the bookkeeping, interleaved, on a melted hard-sphere fluid.
# Each repeat runs the baseline and then every setting once; a setting's figure is the median
# over the repeats of its stepping loop's seconds over the baseline's of the same repeat (the
# two ran a few seconds apart, so a machine busy elsewhere moves both alike).
#
#   make build/bench/bench_versions
#   scripts/bench-versions.sh [COUNT PHI]          (default 32000 0.30)
#
# Environment:
#   SLABS    slab counts to model (default "2 16")
#   WINDOWS  window lengths in time units (default "0.003")
#   LEANS    versions: 1 lean (80 bytes, what a reaction changes) for spheres far from a
#            side, 2 those written past the caches (streaming stores), 0 the ops' whole save
#            everywhere; several, e.g. "0 1 2" (default "1")
#   MODULES  the records and notes of spheres near a side: 0 the bench's own stand-in, 1
#            src/versions.c's (NBEP_VER_MODULE: bench_versions.c says how); "0 1" both
#            (default "0")
#   REPS     repeats, the outer loop (default 5)
#   STEPS    the timed stretch, in steps of the deck's dt = 0.1 after a melt of 20 (default 40)
#   OUT      scratch folder (default build/bench-versions)
#   PERF     1: each run with the bookkeeping once more under `perf record`, and the share of
#            its samples in the bookkeeping's own functions over the rest (what the bookkeeping
#            does itself, without what its memory traffic costs the rest); 0 (default): no perf
# Prints one line per setting (its median time over the baseline's, and perf's share with
# PERF=1) and the bookkeeping's tally (events near a slab's side, notes, messages) from the
# last repeat; the runs' rows are in OUT/rows.csv.
set -u
cd "$(dirname "$0")/.." || exit 1
count=${1:-32000}
phi=${2:-0.30}
SLABS=${SLABS:-2 16}
WINDOWS=${WINDOWS:-0.003}
LEANS=${LEANS:-1}
MODULES=${MODULES:-0}
REPS=${REPS:-5}
STEPS=${STEPS:-40}
OUT=${OUT:-build/bench-versions}
PERF=${PERF:-0}
bin=build/bench/bench_versions
deck=inputs/hard-sphere-fluid.deck
[ -x "$bin" ] || { echo "bench-versions: $bin missing: make $bin" >&2; exit 2; }
mkdir -p "$OUT"
# the box of `count` spheres of diameter 1 at packing fraction phi
side=$(awk -v n="$count" -v p="$phi" 'BEGIN { printf "%.10f", (n * atan2(0, -1) / 6 / p) ^ (1 / 3) }')
set_args=(--set "spheres.[0].count=$count" --set "box.max=[$side, $side, $side]")
melt="$OUT/melt-$count-$phi.h5"
if [ ! -f "$melt" ]; then
    echo "bench-versions: melting $count spheres at phi = $phi (20 steps of 0.1 from the lattice)"
    NBEP_VER_SLABS=0 "$bin" run "$deck" "${set_args[@]}" -n 20 -o "$melt" -q \
        --summary "$OUT/melt.json" 2>/dev/null || { echo "bench-versions: the melt failed" >&2; exit 1; }
fi
field() { sed -n "s/.*\"$1\": *\([0-9.e+-]*\).*/\1/p" "$2"; }
# perf's samples in the bookkeeping's own functions over the rest, in per cent
share() {
    perf report -i "$OUT/perf.data" --stdio --sort sym 2>/dev/null | awk '
        /^ *[0-9.]+%/ { p = $1; sub("%", "", p); tot += p
                        if ($NF ~ /^(ver_event|write_version|read_list|lean_save|cells_save|slab_of|near_slab_side|grow|module_window|nbep_versions_[a-z]*)$/) bk += p }
        END { printf "%.2f", (tot > bk ? 100 * bk / (tot - bk) : 0) }'
}
# one run of setting s:w:l (slabs 0: the baseline), its summary in OUT/s.json; what follows
# the three goes before the binary (perf record)
run_one() {
    local s=$1 w=$2 l=$3 m=$4
    shift 4
    cp "$melt" "$OUT/r.h5"
    # the baseline has no window: any valid one will do
    NBEP_VER_SLABS=$s NBEP_VER_WINDOW=$([ "$s" = 0 ] && echo 1 || echo "$w") NBEP_VER_LEAN=$l \
        NBEP_VER_MODULE=$m \
        "$@" "$bin" run "$deck" "${set_args[@]}" --resume "$OUT/r.h5" -n $((20 + STEPS)) -q \
        --summary "$OUT/s.json" 2>"$OUT/tally-$s-$w-$l-$m.txt"
}
settings=""
for s in $SLABS; do for w in $WINDOWS; do for l in $LEANS; do for m in $MODULES; do
    settings="$settings $s:$w:$l:$m"
done; done; done; done
rows="$OUT/rows.csv"
echo "slabs,window,lean,module,rep,wall_seconds,ratio,collisions,share" >"$rows"
for rep in $(seq "$REPS"); do
    run_one 0 0 0 0 || { echo "bench-versions: a run failed" >&2; exit 1; }
    base=$(field wall_seconds "$OUT/s.json")
    echo "0,0,0,0,$rep,$base,1,$(field collisions "$OUT/s.json")," >>"$rows"
    for swl in $settings; do
        IFS=: read -r s w l m <<<"$swl"
        run_one "$s" "$w" "$l" "$m" || { echo "bench-versions: a run failed" >&2; exit 1; }
        wall=$(field wall_seconds "$OUT/s.json")
        c=$(field collisions "$OUT/s.json")
        sh=""
        if [ "$PERF" = 1 ]; then # the same run again, under perf
            run_one "$s" "$w" "$l" "$m" perf record -q -o "$OUT/perf.data" -- ||
                { echo "bench-versions: perf record failed" >&2; exit 1; }
            sh=$(share)
        fi
        echo "$s,$w,$l,$m,$rep,$wall,$(awk -v a="$wall" -v b="$base" 'BEGIN { printf "%.4f", a / b }'),$c,$sh" >>"$rows"
    done
done
echo "bench-versions: N = $count, phi = $phi, $STEPS steps of 0.1 after the melt, $REPS repeats"
for swl in "0:0:0:0" $settings; do
    IFS=: read -r s w l m <<<"$swl"
    awk -F, -v s="$s" -v w="$w" -v l="$l" -v m="$m" '
        BEGIN { n = 0 }
        NR > 1 && $1 == s && $2 == w && $3 == l && $4 == m { t[n] = $6; r[n] = $7; p[n++] = $9; c = $8 }
        function med(x, n,   i, j, y) {
            for (i = 0; i < n; i++) for (j = i + 1; j < n; j++) if (x[j] < x[i]) { y = x[i]; x[i] = x[j]; x[j] = y }
            return n % 2 ? x[(n - 1) / 2] : (x[n / 2 - 1] + x[n / 2]) / 2 }
        END { if (s == 0) { printf "  baseline: %.3f s (%d collisions)\n", med(t, n), c; exit }
              printf "  %s slabs, window %s, %s versions%s: %.3f times the baseline", s, w, l == 2 ? "streamed lean" : l ? "lean" : "whole", m == 1 ? ", versions.c" : "", med(r, n)
              if (p[0] != "") printf "; perf: the bookkeeping %.1f %% of the rest", med(p, n)
              printf "\n" }' "$rows"
    [ "$s" = 0 ] || sed 's/^bench_versions: /      /' "$OUT/tally-$s-$w-$l-$m.txt"
done
