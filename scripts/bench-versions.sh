#!/usr/bin/env bash
# What the optimistic slab scheme's own bookkeeping would cost a thread per event
# (docs/optimistic-design.md, step 2; tests/bench/bench_versions.c says what it does): one
# binary run without and with the bookkeeping, interleaved, on a melted hard-sphere fluid,
# medians of REPS of the stepping loop's seconds (wall, and CPU less the set-up), and the
# ratios.
#
#   make build/bench/bench_versions
#   scripts/bench-versions.sh [COUNT PHI]          (default 32000 0.30)
#
# Environment:
#   SLABS    slab counts to model (default "2 16")
#   WINDOWS  window lengths in time units (default "0.003")
#   REPS     repeats, the outer loop (default 5)
#   STEPS    the timed stretch, in steps of the deck's dt = 0.1 after a melt of 20 (default 40)
#   OUT      scratch folder (default build/bench-versions)
#   LEAN     1 (default): versions of what an event changes (lean_save); 0: the ops' whole save
#   PERF     1: each run with the bookkeeping once more under `perf record`, and the share of its samples
#            in the bookkeeping's own functions over the rest (a machine busy elsewhere moves
#            this far less than it moves two runs' seconds); 0 (default): no perf
# Prints one line per setting: the median seconds, its ratio to the baseline's median, and
# the bookkeeping's tally (events near a slab's side, notes, messages) from the last repeat.
set -u
cd "$(dirname "$0")/.." || exit 1
count=${1:-32000}
phi=${2:-0.30}
SLABS=${SLABS:-2 16}
WINDOWS=${WINDOWS:-0.003}
REPS=${REPS:-5}
STEPS=${STEPS:-40}
OUT=${OUT:-build/bench-versions}
LEAN=${LEAN:-1}
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
settings="0:0"
for s in $SLABS; do for w in $WINDOWS; do settings="$settings $s:$w"; done; done
rows="$OUT/rows.csv"
echo "slabs,window,rep,wall_seconds,cpu_seconds,setup_seconds,collisions,share" >"$rows"
TIMEFORMAT='%U %S'
[ "$LEAN" = 1 ] && export NBEP_VER_LEAN=1
# perf's samples in the bookkeeping's own functions over the rest, in per cent (PERF=1)
share() {
    perf report -i "$OUT/perf.data" --stdio --sort sym 2>/dev/null | awk '
        /^ *[0-9.]+%/ { p = $1; sub("%", "", p); tot += p
                        if ($NF ~ /^(ver_event|write_version|read_list|lean_save|cells_save|slab_of|near_slab_side|grow)$/) bk += p }
        END { printf "%.2f", (tot > bk ? 100 * bk / (tot - bk) : 0) }'
}
for rep in $(seq "$REPS"); do
    for sw in $settings; do
        s=${sw%%:*} w=${sw#*:}
        cp "$melt" "$OUT/r.h5"
        # the process's CPU seconds (user and system, from bash's time), which a machine
        # busy elsewhere inflates less than the wall's; the baseline (no slabs) has no
        # window: any valid one will do
        cpu=$( { time NBEP_VER_SLABS=$s NBEP_VER_WINDOW=$([ "$s" = 0 ] && echo 1 || echo "$w") \
            "$bin" run "$deck" "${set_args[@]}" --resume "$OUT/r.h5" \
            -n $((20 + STEPS)) -q --summary "$OUT/s.json" 2>"$OUT/tally-$s-$w.txt"; } 2>&1 ) ||
            { echo "bench-versions: a run failed" >&2; exit 1; }
        cpu=$(echo "$cpu" | tail -1 | awk '{ print $1 + $2 }')
        sh=""
        if [ "$PERF" = 1 ] && [ "$s" != 0 ]; then # the same run again, under perf
            cp "$melt" "$OUT/r.h5"
            NBEP_VER_SLABS=$s NBEP_VER_WINDOW=$w perf record -q -o "$OUT/perf.data" -- "$bin" run \
                "$deck" "${set_args[@]}" --resume "$OUT/r.h5" -n $((20 + STEPS)) -q \
                2>/dev/null || { echo "bench-versions: perf record failed" >&2; exit 1; }
            sh=$(share)
        fi
        echo "$s,$w,$rep,$(field wall_seconds "$OUT/s.json"),$cpu,$(field setup_seconds "$OUT/s.json"),$(field collisions "$OUT/s.json"),$sh" >>"$rows"
    done
done
echo "bench-versions: N = $count, phi = $phi, $STEPS steps of 0.1 after the melt, medians of $REPS"
for sw in $settings; do
    s=${sw%%:*} w=${sw#*:}
    # the stepping loop's share of the CPU seconds: the process's less its set-up (the deck,
    # the resume, the first prediction: a wall time, on one busy thread about its CPU time)
    awk -F, -v s="$s" -v w="$w" '
        BEGIN { na = nb = 0 }
        NR > 1 && $1 == 0 { b[nb] = $4; bc[nb++] = $5 - $6 }
        NR > 1 && $1 == s && $2 == w { a[na] = $4; ac[na] = $5 - $6; p[na++] = $8; c = $7 }
        function med(x, n,   i, j, t) {
            for (i = 0; i < n; i++) for (j = i + 1; j < n; j++) if (x[j] < x[i]) { t = x[i]; x[i] = x[j]; x[j] = t }
            return n % 2 ? x[(n - 1) / 2] : (x[n / 2 - 1] + x[n / 2]) / 2 }
        END { mb = med(b, nb); ma = med(a, na); mbc = med(bc, nb); mac = med(ac, na)
              if (s == 0) printf "  baseline: wall %.3f s, CPU %.3f s (%d collisions)\n", ma, mac, c
              else { printf "  %s slabs, window %s: wall %.3f s (%.3f times the baseline), CPU %.3f s (%.3f times)", s, w, ma, ma / mb, mac, mac / mbc
                     if (p[0] != "") printf "; perf: the bookkeeping %.1f %% of the rest", med(p, na)
                     printf "\n" } }' "$rows"
    [ "$s" = 0 ] || sed 's/^bench_versions: /      /' "$OUT/tally-$s-$w.txt"
done
