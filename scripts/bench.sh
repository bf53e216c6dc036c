#!/usr/bin/env bash
# Benchmarks nbep the way the paper's Section 6 measures it, then draws its figures.
#
#   scripts/bench.sh [--quick | --size quick|default|full] [--dry-run] [--plot-only]
#   make bench                      (the default size; BENCH_SIZE=full make bench for a big node)
#
# What runs, in order:
#   1. the micro-benchmarks of tests/bench (barrier crossing, BVH filter, contact-time solvers),
#      each of which checks its own answers before timing;
#   2. the run matrix: bin/nbep run inputs/paper-box.deck for every algorithm (naive,
#      seminaive, predictive, and predictive-grid = predictive with run.neighbors = "grid"),
#      sphere count n, box edge L (box.max = [L,L,L]; the spheres fill the box) and thread
#      count, one CSV row per run in $OUT/runs.csv (the summary's numbers and the coordinates);
#   3. scripts/plot_bench.py: the figures (PNG), the tables (tables.md) and the headline ratios,
#      after checking that the counters agree between thread counts and repeats and that the
#      predictive runs conserve energy and never overlap.
#
# Sizes (BENCH_SIZE or --size; --quick = --size quick):
#   quick    about a minute: n = 256..2048, one repeat, a 20-step window; a smoke test
#   default  about 15 minutes on 2 cores: n = 256..32768 (naive up to 8192), L = 10 with 3
#            repeats, L = 5 and 20 with 1, a 100-step window, threads 1 and 2 (and all cores
#            when there are more than 2)
#   full     a bigger node: naive up to 32768 too, 3 repeats everywhere, a 200-step window,
#            threads 1, 2, 4, ... and all cores
#
# Timing rules, and why:
# - time per step = wall_seconds / steps from the summary: the stepping loop alone, without
#   set-up (for predictive the set-up holds the O(n^2) first predictions, a one-off cost).
# - Every run simulates the same window, t = 0 .. WINDOW * dt. The work of a predictive step
#   follows the physics: the spheres fall and speed up, and at n = 4096 the collisions per step
#   grow from about 1 in the first 0.1 s to about 5 by t = 1 s. Runs of different lengths would
#   measure different physics, so n, algorithm and thread count are compared over one window.
# - A run shorter than MIN_SECONDS (by the rough cost model step_cost) is run again, up to
#   MAX_INNER times, each run a CSV row with the same repeat and its own `inner` index; the
#   plots take the median over those, then over repeats.
# - Repeats are the outer loop and each repeat runs every algorithm and thread count side by
#   side, so a burst of background load hits all variants alike.
# - Output is cut to the minimum (no per-sphere fields, a frame at each end, no /stats) so that
#   the time is the algorithm's, not HDF5's; the counters still come from the summary.
#
# Environment: BENCH_SIZE, BENCH_OUT (results folder, default bench/results[/quick|/full]),
# BENCH_FIGDIR (figures; default docs/figures for the default size, else $BENCH_OUT/figures),
# BENCH_THREADS (e.g. "1 2 4"), BENCH_WINDOW (steps per run), NBEP (the binary, default
# bin/nbep), PYTHON (default /usr/bin/python3: it has numpy and matplotlib, a pyenv shim may not).
set -euo pipefail

cd "$(dirname "$0")/.."

size=${BENCH_SIZE:-default}
dry_run=0
plot_only=0
while [ $# -gt 0 ]; do
    case "$1" in
        --quick) size=quick ;;
        --size) shift; size=${1:?--size needs quick, default or full} ;;
        --size=*) size=${1#--size=} ;;
        --dry-run) dry_run=1 ;;
        --plot-only) plot_only=1 ;;
        -h|--help) sed -n '2,/^set -euo/p' "$0" | sed '$d; s/^# \{0,1\}//'; exit 0 ;;
        *) echo "bench.sh: unknown option '$1' (see --help)" >&2; exit 2 ;;
    esac
    shift
done

NBEP=${NBEP:-bin/nbep}
PYTHON=${PYTHON:-/usr/bin/python3}
DECK=inputs/paper-box.deck
BENCH_BIN=build/bench
NPROC=$(nproc)

# Thread counts: 1, 2, 4, ... up to max and below the core count, then all cores: written as
# the core count when that is a power of two within max (on 2 cores "all" is 2, not run
# twice), else as 0 (nbep resolves it to every core; the CSV holds the count it used).
thread_list() { # max
    local max=$1 t=1 out=""
    while [ "$t" -lt "$NPROC" ] && [ "$t" -le "$max" ]; do out="$out $t"; t=$((t * 2)); done
    if [ "$NPROC" -le "$max" ] && [ $((NPROC & (NPROC - 1))) -eq 0 ]; then
        out="$out $NPROC"
    else
        out="$out 0"
    fi
    echo "${out# }"
}

N_ALL="256 512 1024 2048 4096 8192 16384 32768"
case "$size" in
    quick)
        VOLUMES="10 5 20"; N_MAIN="256 512 1024 2048"; N_SIDE="$N_MAIN"; NAIVE_MAX=2048
        REPEATS=1; SIDE_REPEATS=1; WINDOW=20; MIN_SECONDS=0.02; MAX_INNER=3
        THREADS=$(thread_list 2); BARRIER_ARGS="20000 3"; BVH_ARGS="2048"; PREDICT_ARGS="20000"
        OUT=${BENCH_OUT:-bench/results/quick}; FIGDIR=${BENCH_FIGDIR:-$OUT/figures} ;;
    default)
        VOLUMES="10 5 20"; N_MAIN=$N_ALL; N_SIDE=$N_ALL; NAIVE_MAX=8192
        REPEATS=3; SIDE_REPEATS=1; WINDOW=100; MIN_SECONDS=0.2; MAX_INNER=10
        THREADS=$(thread_list 2); BARRIER_ARGS="200000 5"; BVH_ARGS="32768"
        PREDICT_ARGS="200000"
        OUT=${BENCH_OUT:-bench/results}; FIGDIR=${BENCH_FIGDIR:-docs/figures} ;;
    full)
        VOLUMES="10 5 20"; N_MAIN=$N_ALL; N_SIDE=$N_ALL; NAIVE_MAX=32768
        REPEATS=3; SIDE_REPEATS=3; WINDOW=200; MIN_SECONDS=0.5; MAX_INNER=10
        THREADS=$(thread_list 1024); BARRIER_ARGS="1000000 5"; BVH_ARGS="32768"
        PREDICT_ARGS="1000000"
        OUT=${BENCH_OUT:-bench/results/full}; FIGDIR=${BENCH_FIGDIR:-$OUT/figures} ;;
    *) echo "bench.sh: unknown size '$size' (quick, default or full)" >&2; exit 2 ;;
esac
THREADS=${BENCH_THREADS:-$THREADS}
WINDOW=${BENCH_WINDOW:-$WINDOW}
# The paper's three algorithms, and predictive with run.neighbors = "grid" (beyond the paper: a
# re-prediction tests only the spheres that can reach it soon), when this nbep has that setting.
ALGORITHMS="naive seminaive predictive predictive-grid"
# the help read whole before it is searched: `grep -q` stops at the first match and, under
# pipefail, nbep's SIGPIPE then read as "no such setting" (4 runs in 5 left grid mode out)
help_deck=$("$NBEP" --help-deck 2>/dev/null || true)
if ! grep -q 'run\.neighbors' <<<"$help_deck"; then
    ALGORITHMS="naive seminaive predictive"
fi

# Seconds per step on one thread in the first 0.1 s of the paper-box deck, fitted by eye to
# this code on one 2.6 GHz EPYC core (within about 2x, which is all the planning needs): naive
# tests all n^2/2 pairs; seminaive is about linear; predictive is linear plus re-predictions:
# collisions per step grow as n^2/L^3 and each re-predicts against all n spheres. Set-up:
# predictive predicts every pair once. The grid variant is about linear in n at a given
# density, dearer in a denser box.
step_cost() { # algorithm n L
    awk -v a="$1" -v n="$2" -v L="$3" 'BEGIN {
        if (a == "naive") c = 1.4e-9 * n * n;
        else if (a == "seminaive") c = 4.5e-7 * n;
        else if (a == "predictive-grid") c = 7e-8 * n * (L < 10 ? (10 / L) ^ 1.5 : 1);
        else c = 6e-8 * n + 2e-15 * n * n * n * (10 / L) ^ 3;
        printf "%.9g\n", c }'
}
setup_cost() { # algorithm n
    awk -v a="$1" -v n="$2" 'BEGIN { printf "%.9g\n", (a == "predictive" ? 2.6e-8 * n * n : 0) }'
}
# Runs of one configuration in one repeat: enough for MIN_SECONDS of stepping, 1..MAX_INNER.
inner_for() { # algorithm n L
    awk -v c="$(step_cost "$1" "$2" "$3")" -v w="$WINDOW" -v min="$MIN_SECONDS" \
        -v max="$MAX_INNER" 'BEGIN {
        k = int(min / (c * w)) + 1; if (k > max) k = max; printf "%d\n", k }'
}

# ---- the plan: one line per configuration and repeat, repeats outermost ---------------------
plan=()
for r in $(seq 1 "$REPEATS"); do
    for L in $VOLUMES; do
        if [ "$L" = 10 ]; then
            ns=$N_MAIN
        else
            ns=$N_SIDE
            [ "$r" -le "$SIDE_REPEATS" ] || continue
        fi
        for n in $ns; do
            for a in $ALGORITHMS; do
                [ "$a" = naive ] && [ "$n" -gt "$NAIVE_MAX" ] && continue
                inner=$(inner_for "$a" "$n" "$L")
                for t in $THREADS; do plan+=("$r $L $n $a $t $inner"); done
            done
        done
    done
done

runs=0
estimate=$(for p in "${plan[@]}"; do
    read -r r L n a t inner <<<"$p"
    tt=$t; [ "$tt" = 0 ] && tt=$NPROC
    echo "$(step_cost "$a" "$n" "$L") $tt $(setup_cost "$a" "$n") $inner"
done | awk -v w="$WINDOW" '{ s += $4 * ($1 * w / ($2 > 1 ? 0.7 * $2 : 1) + $3 + 0.05) }
                           END { printf "%.0f", s }')
for p in "${plan[@]}"; do read -r _ _ _ _ _ inner <<<"$p"; runs=$((runs + inner)); done

echo "bench: size $size, $runs runs of $WINDOW steps, about $((estimate / 60)) min" \
     "$((estimate % 60)) s of runs (+ about 1 min of micro-benchmarks); threads: $THREADS;" \
     "volumes L = $VOLUMES"
echo "bench: results in $OUT, figures in $FIGDIR"
if [ "$dry_run" = 1 ]; then
    printf '%s\n' "repeat L n algorithm threads runs" "${plan[@]}"
    exit 0
fi

for f in "$NBEP" "$BENCH_BIN/bench_barrier" "$BENCH_BIN/bench_bvh" "$BENCH_BIN/bench_predict"; do
    [ -x "$f" ] || { echo "bench.sh: $f is missing; build it with 'make bench-programs'" >&2; exit 2; }
done
"$PYTHON" -c 'import numpy, matplotlib' 2>/dev/null ||
    { echo "bench.sh: $PYTHON lacks numpy or matplotlib (set PYTHON=...)" >&2; exit 2; }

mkdir -p "$OUT" "$FIGDIR"
# The results are machine-specific: keep the whole folder out of git.
[ -f bench/results/.gitignore ] || { mkdir -p bench/results; echo '*' > bench/results/.gitignore; }

if [ "$plot_only" = 0 ]; then
    tmp=$(mktemp -d "${TMPDIR:-/tmp}/nbep-bench.XXXXXX")
    trap 'rm -rf "$tmp"' EXIT
    # Run private copies: a rebuild of bin/ during the run (make in another shell) must not
    # swap the program between rows of one table, nor leave it half-written.
    mkdir -p "$tmp/bin"
    cp "$NBEP" "$BENCH_BIN/bench_barrier" "$BENCH_BIN/bench_bvh" "$BENCH_BIN/bench_predict" \
       "$tmp/bin/"
    NBEP=$tmp/bin/$(basename "$NBEP")
    BENCH_BIN=$tmp/bin

    # ---- the machine and build, for the corner notes --------------------------------------
    {
        echo "size=$size"
        echo "date=$(date -u +%Y-%m-%dT%H:%MZ)"
        echo "host=$(hostname)"
        echo "nproc=$NPROC"
        echo "cpu=$(awk -F': ' '/^model name/ { print $2; exit }' /proc/cpuinfo)"
        echo "build=$("$NBEP" --version)"
        echo "tree=$(git describe --always --dirty 2>/dev/null || echo unknown)"
        echo "threads=$THREADS"
        echo "volumes=$VOLUMES"
        echo "window_steps=$WINDOW"
        echo "repeats=$REPEATS"
        echo "omp_wait_policy=${OMP_WAIT_POLICY:-unset}"
    } > "$OUT/meta.txt"

    # ---- 1. micro-benchmarks (each checks its answers first and exits non-zero if wrong) ---
    echo "bench: barrier crossing (bench_barrier $BARRIER_ARGS)"
    # shellcheck disable=SC2086
    "$BENCH_BIN/bench_barrier" $BARRIER_ARGS | tee "$OUT/barrier.csv"
    echo "bench: BVH filter (bench_bvh $BVH_ARGS)"
    # shellcheck disable=SC2086
    "$BENCH_BIN/bench_bvh" $BVH_ARGS | tee "$OUT/bvh.csv"
    echo "bench: contact-time solvers (bench_predict $PREDICT_ARGS)"
    # shellcheck disable=SC2086
    "$BENCH_BIN/bench_predict" $PREDICT_ARGS | tee "$OUT/predict.txt"

    # ---- 2. the run matrix ----------------------------------------------------------------
    csv=$OUT/runs.csv
    echo "algorithm,n,volume,box_L,threads,threads_requested,repeat,inner,steps,wall_seconds," \
         "time_per_step,setup_seconds,checks,predictions,collisions,sphere_collisions," \
         "plane_collisions,quiet_steps,peak_rss_bytes,prediction_rate,quiet_fraction," \
         "energy_rel_drift,max_overlap_rel,loadavg,exit_status" | tr -d ' ' > "$csv"
    start=$(date +%s)
    k=0
    for p in "${plan[@]}"; do
        read -r r L n a t inner <<<"$p"
        k=$((k + 1))
        tps_all=""
        for i in $(seq 1 "$inner"); do
            load=$(cut -d' ' -f1 /proc/loadavg)
            rc=0
            variant=(-a "$a")
            [ "$a" = predictive-grid ] && variant=(-a predictive --set 'run.neighbors="grid"')
            "$NBEP" run "$DECK" "${variant[@]}" -t "$t" -n "$WINDOW" --quiet -o "$tmp/run.h5" \
                --set "spheres.[0].count=$n" --set "box.max=[$L,$L,$L]" \
                --set "output.every=$WINDOW" --set 'output.fields=[]' --set output.stats=false \
                --summary "$tmp/run.json" 2> "$tmp/run.err" || rc=$?
            if [ "$rc" -ne 0 ] || [ ! -s "$tmp/run.json" ]; then
                echo "bench: FAILED ($rc): $a n=$n L=$L t=$t: $(head -c 300 "$tmp/run.err")" >&2
                echo '{}' > "$tmp/run.json"
                [ "$rc" -ne 0 ] || rc=1
            fi
            line=$("$PYTHON" - "$tmp/run.json" "$a" "$n" "$L" "$t" "$r" "$i" "$WINDOW" "$load" \
                   "$rc" <<'EOF'
import json, sys
path, a, n, L, t, r, i, steps, load, rc = sys.argv[1:]
d = json.load(open(path))
g = lambda k: d.get(k, "")
steps = int(d.get("steps", steps))
checks, coll = d.get("checks"), d.get("collisions")
row = [a, n, float(L) ** 3, L, g("threads"), t, r, i, steps, g("wall_seconds"),
       d["wall_seconds"] / steps if "wall_seconds" in d and steps else "",
       g("setup_seconds"), checks if checks is not None else "", g("predictions"),
       coll if coll is not None else "", g("sphere_collisions"), g("plane_collisions"),
       g("quiet_steps"), g("peak_rss_bytes"),
       coll / checks if checks else "", d["quiet_steps"] / steps if "quiet_steps" in d else "",
       g("energy_rel_drift"), g("max_overlap_rel"), load, rc]
print(",".join(repr(x) if isinstance(x, float) else str(x) for x in row))
EOF
)
            echo "$line" >> "$csv"
            rm -f "$tmp/run.h5" "$tmp/run.json"
            tps=$(echo "$line" | cut -d, -f11)
            tps_all="$tps_all $(printf '%.3g' "${tps:-nan}")"
        done
        el=$(($(date +%s) - start))
        printf 'bench: [%d/%d %dm%02ds] r%s L=%s n=%s %s t=%s: s/step%s\n' \
            "$k" "${#plan[@]}" $((el / 60)) $((el % 60)) "$r" "$L" "$n" "$a" "$t" "$tps_all"
    done
fi

# ---- 3. figures, tables, headline -----------------------------------------------------------
"$PYTHON" scripts/plot_bench.py --results "$OUT" --figdir "$FIGDIR"
