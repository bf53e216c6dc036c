#!/usr/bin/env bash
# Dense hard-sphere fluids: collisions per wall second of nbep's predictive algorithm with
# run.neighbors = "cells" in a periodic box (and "grid" in a closed box of the same volume when
# ENGINES asks: grid mode has no periodic boundaries), beside Smallenburg's EDMD (Single
# variant) when a copy of it is available, and peak memory per sphere.
#
#   scripts/bench-dense.sh            (make bench-dense)
#   EDMD_DIR=/path/to/EDMD scripts/bench-dense.sh
#
# Environment:
#   EDMD_DIR     a checkout of github.com/FSmallenburg/EDMD (its Single/ folder is copied to a
#                scratch folder, its parameters set there, built with its own Makefile; nothing
#                of it enters nbep). Unset or missing: EDMD is skipped, with a message.
#   N            spheres (default 32000 = 4 x 20^3, as EDMD's FCC start wants)
#   PHIS         packing fractions (default "0.30 0.50")
#   THREADS      nbep thread counts (default "1 2")
#   ENGINES      nbep modes (default "cells"; add "grid" for the closed-box grid mode)
#   REPS         repeats; the table shows medians (default 3)
#   SCALE        multiplies every simulated time (default 1; 0.2 for a smoke run)
#   OUT          where the raw rows go (default build/bench-dense)
#
# The scenes: N spheres of diameter 1, mass 1, kT = 1 (nbep: speed sqrt(3) in random
# directions; EDMD: Gaussian velocities scaled to kT = 1) in a periodic cube of side L,
# L^3 = N pi / (6 phi), as EDMD's (nbep's grid mode, which has no periodic boundaries: a closed
# box of that volume). nbep starts on a simple cubic lattice, EDMD from its FCC crystal.
# Each run simulates a fixed time chosen per engine so that it takes a few seconds (the grid
# mode is far slower on dense scenes and simulates less); collisions per second are
# collisions / wall seconds: nbep's stepping loop (the summary's wall_seconds), EDMD's whole
# process (its set-up, an FCC build and neighbour lists, is a small part). Repeats are the
# outer loop and every engine runs once per repeat, so background load hits all alike.
set -u
cd "$(dirname "$0")/.."
N=${N:-32000}
PHIS=${PHIS:-"0.30 0.50"}
THREADS=${THREADS:-"1 2"}
ENGINES=${ENGINES:-cells}
REPS=${REPS:-3}
SCALE=${SCALE:-1}
OUT=${OUT:-build/bench-dense}
mkdir -p "$OUT"
rows="$OUT/rows.csv"
echo "engine,phi,threads,rep,collisions,seconds,rss_bytes" >"$rows"

# simulated time (in tau) per engine and phi: a few seconds each on one core
sim_time() { # engine phi
    case "$1:$2" in
    grid:0.30) echo 0.2 ;; grid:*) echo 0.01 ;;
    cells:0.30) echo 1.0 ;; cells:*) echo 0.4 ;;
    edmd:0.30) echo 10 ;; edmd:*) echo 5 ;;
    esac
}
scaled() { awk -v a="$1" -v s="$SCALE" 'BEGIN { printf "%.6g", a * s }'; }

edmd_bin=""
if [ -n "${EDMD_DIR:-}" ] && [ -f "$EDMD_DIR/Single/mdSingle.c" ]; then
    edmd_src="$OUT/edmd-src"
    rm -rf "$edmd_src" && cp -r "$EDMD_DIR/Single" "$edmd_src"
    echo "EDMD: building $EDMD_DIR/Single in $edmd_src with its own Makefile"
else
    echo "EDMD: skipped (set EDMD_DIR to a checkout of github.com/FSmallenburg/EDMD)"
fi

# EDMD's parameters are globals in its source: a build per packing fraction and time.
edmd_build() { # phi time -> path of the binary
    local dir="$OUT/edmd-$1-$2"
    if [ ! -x "$dir/md" ]; then
        rm -rf "$dir" && cp -r "$edmd_src" "$dir"
        sed -i -e "s/^double maxtime = [0-9.e+-]*;/double maxtime = $2;/" \
            -e "s/^double writeinterval = [0-9.e+-]*;/double writeinterval = $2;/" \
            -e "s/^double snapshotinterval = [0-9.e+-]*;/double snapshotinterval = $2;/" \
            -e "s/^int initialconfig = 0;/int initialconfig = 1;/" \
            -e "s/^double packfrac = [0-9.e+-]*;/double packfrac = $1;/" \
            -e "s/^int N = [0-9]*;/int N = $N;/" \
            -e "s/^const int usethermostat = 1;/const int usethermostat = 0;/" "$dir/mdSingle.c"
        (cd "$dir" && make -s >build.log 2>&1) || { echo "EDMD build failed: $dir/build.log" >&2; return 1; }
    fi
    echo "$dir"
}

deck="$OUT/fluid.deck"
run_nbep() { # mode phi threads rep
    local T L steps=10 dt
    T=$(scaled "$(sim_time "$1" "$2")")
    dt=$(awk -v t="$T" -v s=$steps 'BEGIN { printf "%.6g", t / s }')
    L=$(awk -v n="$N" -v p="$2" 'BEGIN { printf "%.12g", (n * atan2(0, -1) / (6 * p)) ^ (1 / 3) }')
    local per="true"
    [ "$1" = grid ] && per="false"
    cat >"$deck" <<EOF
run: { algorithm = "predictive"; steps = $steps; dt = $dt; threads = $3; seed = $4; neighbors = "$1"; };
box: { min = [0.0, 0.0, 0.0]; max = [$L, $L, $L]; periodic = [$per, $per, $per]; };
spheres = ( { count = $N; radius = 0.5; mass = 1.0; place = "lattice"; speed = 1.7320508075688772; } );
output: { file = "$OUT/fluid.h5"; every = 1000000; fields = []; stats = false; };
EOF
    local s
    s=$(bin/nbep run "$deck" --quiet --summary -) || { echo "nbep failed: $deck" >&2; return 1; }
    local col sec rss
    col=$(echo "$s" | sed -n 's/.*"collisions": *\([0-9]*\).*/\1/p')
    sec=$(echo "$s" | sed -n 's/.*"wall_seconds": *\([0-9.e+-]*\).*/\1/p')
    rss=$(echo "$s" | sed -n 's/.*"peak_rss_bytes": *\([0-9]*\).*/\1/p')
    echo "$1,$2,$3,$4,$col,$sec,$rss" >>"$rows"
}

run_edmd() { # phi rep
    local T dir t0 t1 log col rss
    T=$(scaled "$(sim_time edmd "$1")")
    dir=$(edmd_build "$1" "$T") || return 1
    log="$dir/run-$2.log"
    t0=$(date +%s.%N)
    (cd "$dir" && /usr/bin/time -f "RSS %M" ./md >"run-$2.log" 2>&1)
    t1=$(date +%s.%N)
    col=$(sed -n 's/^Simtime: .*Collisions: \([0-9]*\),.*/\1/p' "$log" | tail -1)
    rss=$(sed -n 's/^RSS \([0-9]*\)/\1/p' "$log")
    echo "edmd,$1,1,$2,$col,$(awk -v a="$t0" -v b="$t1" 'BEGIN { print b - a }'),$((rss * 1024))" >>"$rows"
}

for rep in $(seq "$REPS"); do
    for phi in $PHIS; do
        for nt in $THREADS; do
            for engine in $ENGINES; do
                run_nbep "$engine" "$phi" "$nt" "$rep"
            done
        done
        [ -n "${edmd_src:-}" ] && run_edmd "$phi" "$rep"
    done
    echo "repeat $rep of $REPS done"
done

# medians over repeats, then the table and the ratios
python3 - "$rows" "$N" <<'PYEOF'
import csv, statistics, sys
rows = list(csv.DictReader(open(sys.argv[1])))
n = int(sys.argv[2])
groups = {}
for r in rows:
    if not r["collisions"] or not r["seconds"]:
        continue
    key = (r["engine"], r["phi"], int(r["threads"]))
    groups.setdefault(key, []).append(r)
med = {}
for key, rs in groups.items():
    rate = statistics.median(int(r["collisions"]) / float(r["seconds"]) for r in rs)
    rss = statistics.median(int(r["rss_bytes"] or 0) for r in rs)
    med[key] = (rate, rss, len(rs))
print(f"\nN = {n}; collisions per wall second, medians of the repeats")
print("| engine | phi | threads | collisions/s | peak RSS / sphere | runs |")
print("| --- | --- | --- | --- | --- | --- |")
for key in sorted(med):
    rate, rss, k = med[key]
    print(f"| {key[0]} | {key[1]} | {key[2]} | {rate/1e3:.1f} k | {rss/n/1e3:.2f} kB | {k} |")
print("\nratios")
for (eng, phi, nt), (rate, _, _) in sorted(med.items()):
    if eng != "cells":
        continue
    g = med.get(("grid", phi, nt))
    e = med.get(("edmd", phi, 1))
    c1 = med.get(("cells", phi, 1))
    parts = [f"phi {phi}, {nt} thread(s)"]
    if g:
        parts.append(f"cells/grid = {rate / g[0]:.1f}x")
    if e:
        parts.append(f"cells/EDMD = {rate / e[0]:.2f}")
    if c1 and nt != 1:
        parts.append(f"cells {nt} threads / 1 thread = {rate / c1[0]:.2f}")
    print("  " + "; ".join(p for p in parts if p))
PYEOF
