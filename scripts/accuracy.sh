#!/usr/bin/env bash
# Accuracy against cost: naive, seminaive and predictive over a range of dt, on a gas and on
# scenes with an analytic answer; then the table and the figure. See docs/accuracy.md.
#
#   scripts/accuracy.sh [--quick] [--plot-only] [--no-contact]
#   make accuracy [ACC_ARGS=--quick]
#
#   --quick       dt = 1e-2, 1e-3, 1e-4, 1e-5, one repeat, a shorter gas run, 500 contact cases
#                 per class (under a minute); default: seven dt from 1e-2 to 1e-5, three
#                 repeats, 4000 cases per class (about 8 minutes on 2 cores: a repeat of part 1
#                 takes about 72 s)
#   --plot-only   redraw the table and figure from an existing CSV
#   --no-contact  skip part 2: build/bench/bench_contact (the contact-time solvers against a
#                 binary128 reference; `make bench` or `make accuracy` builds it), whose table
#                 goes to $OUT/contact.md, and the check of its reference in 60-digit mpmath
#
# What runs: scripts/accuracy.py first checks its missed-collision detector on a built case
# (fast spheres that pass through each other between frames: naive must miss exactly three,
# predictive none) and stops if it fails; then every (scene, algorithm, dt) runs for the same
# simulated time with minimal output (timing, energy, overlap, final positions against the
# analytic answer), repeats outermost; then a short run with a frame every step per
# (scene, algorithm, dt) for the missed-collision count.
#
# Results (machine-specific, kept out of git): $OUT/accuracy.csv, table.md, meta.json;
# figure: $FIG.
# Environment: ACC_OUT (default bench/accuracy, or bench/accuracy/quick with --quick),
# ACC_FIG (default docs/figures/accuracy.png; $OUT/accuracy.png with --quick),
# ACC_THREADS (default 1: the scenes are small, and on a noisy 2-core machine a second thread
# mostly adds barrier waits), NBEP (default bin/nbep), PYTHON (default /usr/bin/python3: it has
# numpy, h5py and matplotlib; a pyenv shim may not).
set -euo pipefail

cd "$(dirname "$0")/.."

quick=0
plot_only=0
contact=1
while [ $# -gt 0 ]; do
    case "$1" in
        --quick) quick=1 ;;
        --plot-only) plot_only=1 ;;
        --no-contact) contact=0 ;;
        -h|--help) sed -n '2,/^set -euo/p' "$0" | sed '$d; s/^# \{0,1\}//'; exit 0 ;;
        *) echo "accuracy.sh: unknown option '$1' (see --help)" >&2; exit 2 ;;
    esac
    shift
done

NBEP=${NBEP:-bin/nbep}
PYTHON=${PYTHON:-/usr/bin/python3}
if [ "$quick" = 1 ]; then
    OUT=${ACC_OUT:-bench/accuracy/quick}
    FIG=${ACC_FIG:-$OUT/accuracy.png}
    mode=(--quick)
else
    OUT=${ACC_OUT:-bench/accuracy}
    FIG=${ACC_FIG:-docs/figures/accuracy.png}
    mode=()
fi

if [ "$contact" = 1 ] && [ "$plot_only" = 0 ] && [ ! -x build/bench/bench_contact ]; then
    echo "accuracy.sh: build/bench/bench_contact is missing; build with 'make bench'" \
         "(or pass --no-contact)" >&2
    exit 2
fi
"$PYTHON" -c 'import numpy, h5py, matplotlib' 2>/dev/null ||
    { echo "accuracy.sh: $PYTHON lacks numpy, h5py or matplotlib (set PYTHON=...)" >&2; exit 2; }
mkdir -p "$OUT"
# The results are machine-specific: keep the whole folder out of git.
[ -f bench/accuracy/.gitignore ] ||
    { mkdir -p bench/accuracy; echo '*' > bench/accuracy/.gitignore; }

if [ "$plot_only" = 1 ]; then
    exec "$PYTHON" scripts/accuracy.py report "$OUT/accuracy.csv" --fig "$FIG"
fi
[ -x "$NBEP" ] || { echo "accuracy.sh: $NBEP is missing; build with 'make'" >&2; exit 2; }
"$PYTHON" scripts/accuracy.py run "${mode[@]}" --out "$OUT" --fig "$FIG" --nbep "$NBEP" \
    --threads "${ACC_THREADS:-1}"

if [ "$contact" = 1 ]; then
    # Each case's inputs and reference go to contact-cases.txt, re-derived by mpmath below.
    echo "accuracy: contact-time solvers (bench_contact ${mode[*]})"
    build/bench/bench_contact "${mode[@]}" --csv "$OUT/contact.csv" \
        --dump "$OUT/contact-cases.txt" | tee "$OUT/contact.md"
    per_class=200
    [ "$quick" = 1 ] && per_class=50
    "$PYTHON" -c 'import mpmath' 2>/dev/null &&
        "$PYTHON" scripts/accuracy.py contact-check "$OUT/contact-cases.txt" \
            --per-class "$per_class" | tee "$OUT/contact-check.txt" ||
        echo "accuracy.sh: no mpmath: the reference was not re-derived" >&2
fi
