#!/usr/bin/env bash
# Dense hard-sphere fluids at equilibrium: collisions per wall second of nbep's predictive
# algorithm with run.neighbors = "cells" in a periodic box, beside Smallenburg's EDMD (Single
# variant) on the very same fluid when a copy of it is available, and peak memory per sphere.
#
#   scripts/bench-dense.sh            (make bench-dense)
#   EDMD_DIR=/path/to/EDMD scripts/bench-dense.sh
#
# Environment:
#   EDMD_DIR     a checkout of github.com/FSmallenburg/EDMD (its Single/ folder is copied to a
#                scratch folder, its parameters set there, built with its own Makefile; nothing
#                of it enters nbep). Unset or missing: EDMD is skipped, with a message.
#   NS           sphere counts (default "32000"; "32000 256000" for the large fluid too)
#   PHIS         packing fractions (default "0.30 0.50")
#   THREADS      nbep thread counts (default "1 2")
#   REPS         repeats; the table shows medians (default 3)
#   SCALE        multiplies every measured stretch of simulated time (default 1; 0.2: smoke)
#   OUT          where the raw rows and the scratch builds go (default build/bench-dense)
#   NBEP         the nbep binary (default bin/nbep; a wrapper script for a node that lacks the
#                libraries, for example)
#   PAIRED       1: nbep's one-thread run and EDMD's measured run at the same time, one on each
#                of the first two CPUs this process may use (taskset; they swap CPUs each
#                repeat; fewer than two: exit 2), so that both meet
#                the same load, as scripts/ab-pair.sh pairs two builds of nbep; the table adds
#                the median of the repeats' own ratios. On this project's shared 2-core machine
#                one engine's repeats, run one after the other, differed by up to 1.6 times
#                (2026-12-01), and so did the ratios of medians. The two share the caches and
#                the memory while they run, as they do not when run apart. EDMD's set-up run
#                (to 0.1) runs alone, before the pair. Other thread counts run as without it.
#   CEILING      1: beside each run on k > 1 threads, k one-thread runs of the same stretch at
#                once, each held to one of the first k CPUs this process may use (fewer, or no
#                taskset: exit 2), their rates added: what the machine gives k independent
#                threads of this work at that moment, the most any parallel scheme could give
#                (table rows "apart"). A row of ratios then says how much of it the k-thread run
#                got. On this project's machine the two virtual CPUs ran one thread 1.9 s and
#                2.8 s on the same stretch in the same minute (2026-12-07), so two threads over
#                one there is bounded by the slower CPU, not by the scheme.
#   COUNT        1: instead of timing, count (make bench-dense-count). Each engine runs under
#                valgrind's cachegrind on the same melt for two lengths of simulated time, and
#                the table gives per collision of the difference: instructions, first-level data
#                cache misses and misses of a second level the size of this machine's (L2 from
#                lscpu; CG_L2 = bytes,ways overrides it), the caches simulated (so the same
#                figures on any machine, whatever its load). A machine's speed is roughly
#                instructions / IPC plus misses times their latency; counting tells which of the
#                two an engine spends more of, which timing on a shared machine cannot.
#
# The scene: N spheres of diameter 1, mass 1, kT = 1 in a periodic cube of side L,
# L^3 = N pi / (6 phi) (inputs/hard-sphere-fluid.deck is the N = 32000, phi = 0.30 one).
# Both engines are timed on the equilibrium fluid, not on their starts: nbep starts from a
# simple cubic lattice (speed sqrt(3) in random directions), which melts within a time unit,
# run once to T1 = 1 (the melt); each timed run resumes that file (--resume, on a copy) and
# steps on to T1 + S: its summary counts the whole run's collisions (since 2026-11-30: from
# step 0, the melt's too, which are taken off) and times its stepping loop alone (the resumed
# run's set-up, reading the frame and the first predictions, is outside wall_seconds), so the
# rate is the run's collisions since the melt / wall_seconds. (Until fe29f48 it was the difference of
# two runs from the lattice, to T1 and to T1 + S: twice the runs, and one slow short run could
# give an impossible ratio.) EDMD starts from nbep's fluid at T1 (written as its
# init.sph; its own FCC start would stay crystalline at phi = 0.50, a different scene with a
# third fewer collisions), with its Gaussian velocities, and is timed the same way: two runs,
# to 0.1 and to 0.1 + S, whole processes (so its set-up cancels). Repeats are the outer loop and
# every engine runs once per repeat, so background load hits all alike; medians are reported,
# and the ratios are of medians taken in the same run. Beside wall time, each row has the
# processes' CPU time (user + system, /usr/bin/time): EDMD's differenced the same way, nbep's
# less its set-up's wall seconds (one thread's: its set-up is mostly serial). CPU time leaves
# out the time a process waited for a core, not the slowdown another job causes through the
# shared caches and memory: on this project's 2-core machine the two ratios came out the same;
# where a machine is oversubscribed the CPU-time one is the steadier.
#
# Beside each multi-thread run, the time a cache line takes to pass between two cores
# (scripts/handover.c, built in OUT; median of 5 stretches, before and after the run): the team
# loop passes a few lines between its threads for each event, so a repeat's two-thread ratio
# follows it. On this project's 2-core virtual machine it was about 28 ns most of the time and
# about 160 ns in stretches of minutes (the host had put the two virtual CPUs on cores that
# share no cache); the table lists each repeat's ratio with it.
set -u
cd "$(dirname "$0")/.." || exit 1
NS=${NS:-32000}
PHIS=${PHIS:-"0.30 0.50"}
THREADS=${THREADS:-"1 2"}
REPS=${REPS:-3}
SCALE=${SCALE:-1}
OUT=${OUT:-build/bench-dense}
NBEP=${NBEP:-bin/nbep}
PY=${PYTHON:-/usr/bin/python3}
PAIRED=${PAIRED:-0}
CEILING=${CEILING:-0}
# the CPUs this process may run on, in order (Cpus_allowed_list, "0-15" or "2,5-7"): PAIRED
# holds its runs to the first two, CEILING its k runs at once to the first k, not 0 and 1 and so
# on, which a job's cpuset may not hold; too few, or no taskset: refused
read -r -a CPUS < <(sed -n 's/^Cpus_allowed_list:[[:space:]]*//p' /proc/self/status |
    awk -F, '{ for (i = 1; i <= NF; i++) { n = split($i, r, "-"); for (c = r[1]; c <= r[n]; c++) printf "%d ", c } }')
if [ "$PAIRED" = 1 ]; then
    CPU_A=${CPUS[0]:-} CPU_B=${CPUS[1]:-}
    if [ -z "$CPU_B" ] || ! command -v taskset >/dev/null; then
        echo "bench-dense.sh: PAIRED=1 needs two CPUs to run on and taskset (util-linux); this process may use CPUs ${CPU_A:-none}" >&2
        exit 2
    fi
fi
if [ "$CEILING" = 1 ]; then
    most=$(printf '%s\n' $THREADS | sort -n | tail -1)
    if [ "${#CPUS[@]}" -lt "$most" ] || ! command -v taskset >/dev/null; then
        echo "bench-dense.sh: CEILING=1 needs $most CPUs to run on (THREADS up to $most) and taskset (util-linux); this process may use ${#CPUS[@]}" >&2
        exit 2
    fi
fi
mkdir -p "$OUT"
rows="$OUT/rows.csv"
echo "engine,n,phi,threads,rep,collisions,seconds,rss_bytes,cpu_seconds,handover_ns" >"$rows"
# the hand-over probe: built here; on a node without a compiler, a copy already in OUT is used,
# and with neither the column stays empty
handover="$OUT/handover"
if command -v cc >/dev/null; then
    cc -std=c11 -O2 -pthread scripts/handover.c -o "$handover" || { echo "handover probe: build failed" >&2; exit 1; }
elif [ ! -x "$handover" ]; then
    echo "handover probe: skipped (no cc, none in $OUT)"
    handover=""
fi

# the stretch S of simulated time measured, per phi: 0.6 million collisions per 32000 spheres,
# and never fewer than 96000 spheres' worth, 1.9 million (chosen when the rate was a difference
# of two runs, which the machine's noise swamped at about a second a stretch; EDMD's still is,
# and keeping the stretches keeps the tables comparable)
stretch() { # n phi
    awk -v n="$1" -v p="$2" -v s="$SCALE" \
        'BEGIN { f = n < 96000 ? 96000 / n : 1; printf "%.6g", (p < 0.4 ? 4.0 : 1.0) * f * s }'
}
side() { awk -v n="$1" -v p="$2" 'BEGIN { printf "%.12g", (n * atan2(0, -1) / (6 * p)) ^ (1 / 3) }'; }
T1=1

edmd_src=""
if [ -n "${EDMD_DIR:-}" ] && [ -f "$EDMD_DIR/Single/mdSingle.c" ]; then
    edmd_src="$OUT/edmd-src"
    rm -rf "$edmd_src" && cp -r "$EDMD_DIR/Single" "$edmd_src"
    echo "EDMD: building $EDMD_DIR/Single in $OUT with its own Makefile"
else
    echo "EDMD: skipped (set EDMD_DIR to a checkout of github.com/FSmallenburg/EDMD)"
fi

deck() { # n phi steps dt threads file fields [every] -> path of the deck (one per output
    # file: runs at once, CEILING's, each write their own)
    local d="$OUT/fluid-$1-$2-$3-$5-$(basename "$6" .h5).deck" L
    L=$(side "$1" "$2")
    cat >"$d" <<EOF
run: { algorithm = "predictive"; steps = $3; dt = $4; threads = $5; seed = 1; neighbors = "cells"; };
box: { min = [0.0, 0.0, 0.0]; max = [$L, $L, $L]; periodic = [true, true, true]; };
spheres = ( { count = $1; radius = 0.5; mass = 1.0; place = "lattice"; speed = 1.7320508075688772; } );
output: { file = "$6"; every = ${8:-$3}; fields = [$7]; stats = false; };
EOF
    echo "$d"
}

# EDMD's parameters are globals in its source: a build per (n, phi, time), reading init.sph,
# the fluid nbep reaches at T1.
edmd_build() { # n phi time [cg] -> path of the build (cg: for cachegrind, AVX2 at most)
    local dir="$OUT/edmd-$1-$2-$3${4:+-$4}"
    if [ ! -x "$dir/md" ]; then
        rm -rf "$dir" && cp -r "$edmd_src" "$dir"
        [ -n "${4:-}" ] && sed -i -e "s/-march=native/-march=x86-64-v3/" "$dir/Makefile"
        sed -i -e "s/^double maxtime = [0-9.e+-]*;/double maxtime = $3;/" \
            -e "s/^double writeinterval = [0-9.e+-]*;/double writeinterval = $3;/" \
            -e "s/^double snapshotinterval = [0-9.e+-]*;/double snapshotinterval = $3;/" \
            -e "s/^int initialconfig = [0-9]*;/int initialconfig = 0;/" \
            -e "s/^const int usethermostat = 1;/const int usethermostat = 0;/" "$dir/mdSingle.c"
        (cd "$dir" && make -s >build.log 2>&1) || { echo "EDMD build failed: $dir/build.log" >&2; return 1; }
        ln -sf "../init-$1-$2.sph" "$dir/init.sph" # (a folder of builds can travel without it)
    fi
    echo "$dir"
}

# nbep's fluid at T1 (steps of 0.05, as the timed runs': the frame at T1 is where they resume),
# and as EDMD's init.sph (positions wrapped into the box, radius 0.5)
# Steps of DT (an update and energy sum of every sphere each: a few percent of a step).
DT=0.05
steps_to() { awk -v t="$1" -v dt="$DT" 'BEGIN { printf "%d", t / dt + 0.5 }'; } # time -> steps
STEPS1=$(steps_to "$T1")
FIELDS='"position", "velocity"' # the melt's, which every run resuming it keeps
melt() { # n phi
    local h5="$OUT/melt-$1-$2.h5" d
    d=$(deck "$1" "$2" "$STEPS1" "$DT" 1 "$h5" "$FIELDS")
    "$NBEP" run "$d" --quiet || { echo "nbep failed: $d" >&2; return 1; }
    "$PY" - "$h5" "$(side "$1" "$2")" "$OUT/init-$1-$2.sph" <<'PYEOF' || return 1
import sys, h5py
f = h5py.File(sys.argv[1], "r"); L = float(sys.argv[2])
p = f["/frames/position"][-1]
with open(sys.argv[3], "w") as o:
    o.write("%d\n%.12f %.12f %.12f\n" % (len(p), L, L, L))
    for x in p:
        o.write("a %.15f %.15f %.15f 0.5\n" % (x[0] % L, x[1] % L, x[2] % L))
PYEOF
}

summary_field() { sed -n "s/.*\"$1\": *\([0-9.e+-]*\).*/\1/p"; }
# the collisions of the melt of n phi, up to its last frame, where the timed runs resume
melt_collisions() { "$NBEP" info "$OUT/melt-$1-$2.h5" | summary_field collisions; }

# timed CMD...: runs it (stdout kept) and records its CPU time and peak RSS, which cpu_of
# (user + system, seconds) and rss_of (bytes) read back; minus A B prints B - A. Without GNU
# time (GNU_TIME, default /usr/bin/time) the command runs untimed and those columns are 0.
TIME_OUT="$(cd "$OUT" && pwd)/time.txt"
# PIN, where set (PAIRED): the CPU a timed run is held to
pinned() { if [ -n "${PIN:-}" ]; then echo taskset -c "$PIN"; fi; }
GNU_TIME=${GNU_TIME:-/usr/bin/time}
if [ -x "$GNU_TIME" ]; then
    timed() { "$GNU_TIME" -f "%U %S %M" -o "$TIME_OUT" "$@"; }
else
    echo "CPU time and EDMD's memory: not measured (no $GNU_TIME)"
    timed() { echo "0 0 0" >"$TIME_OUT"; "$@"; }
fi
cpu_of() { awk 'END { print $1 + $2 }' "$TIME_OUT"; } # the last line: a failed command's
rss_of() { awk 'END { print $3 * 1024 }' "$TIME_OUT"; } # status line comes first
minus() { awk -v a="$1" -v b="$2" 'BEGIN { print b - a }'; }

probe() { [ -n "$handover" ] && "$handover"; } # the hand-over now, or nothing

run_nbep() { # n phi threads rep [tag]: the row's engine and thread count are ENGINE's and
    # GROUP's where set (CEILING's runs at once: "apart", k), the output file run<tag>.h5
    local out="$OUT/run${5:-}.h5" d u s c h1="" h2="" ho=""
    # to T1 + S, resuming the melt's frame at T1: a frame each T1, since a cells run resumes
    # only from a frame at a multiple of output.every, with the melt's fields (a resume takes
    # the deck that made the file: fields = [] is refused since 2c91e16, and every nbep run
    # failed here until 2026-11-30; a frame of positions and velocities is 1.5 MB at N = 32000,
    # written in about a millisecond, beside the cells' rebuild each frame already costs)
    d=$(deck "$1" "$2" "$(steps_to "$(awk -v s="$(stretch "$1" "$2")" -v t="$T1" 'BEGIN { print t + s }')")" \
        "$DT" "$3" "$out" "$FIELDS" "$STEPS1")
    cp "$OUT/melt-$1-$2.h5" "$out"
    [ "$3" -gt 1 ] && h1=$(probe)
    # shellcheck disable=SC2046
    s=$(timed $(pinned) "$NBEP" run "$d" --resume "$out" --quiet --summary -) || { echo "nbep failed: $d" >&2; return 1; }
    # CPU seconds less the set-up's wall seconds (0 where GNU time did not measure)
    u=$(awk -v c="$(cpu_of)" -v w="$(echo "$s" | summary_field setup_seconds)" 'BEGIN { print (c > 0 ? c - w : 0) }')
    [ "$3" -gt 1 ] && h2=$(probe) && ho="$h1 $h2"
    # the collisions since the melt's frame: the summary counts from step 0 (the melt's too)
    c=$(minus "$(melt_collisions "$1" "$2")" "$(echo "$s" | summary_field collisions)")
    echo "${ENGINE:-nbep},$1,$2,${GROUP:-$3},$4,$c,$(echo "$s" | summary_field wall_seconds),$(echo "$s" | summary_field peak_rss_bytes),$u,$ho" >>"$rows"
}

run_apart() { # n phi k rep: k one-thread runs at once, the i-th held to the i-th CPU (CEILING)
    local i pids=()
    for ((i = 0; i < $3; i++)); do
        ENGINE=apart GROUP=$3 PIN=${CPUS[i]} TIME_OUT="$TIME_OUT.apart$i" \
            run_nbep "$1" "$2" 1 "$4" "-apart$i" &
        pids+=($!)
    done
    # every run waited for, so that none still writes when a failure ends the script
    local failed=0
    for i in "${pids[@]}"; do wait "$i" || failed=1; done
    return "$failed"
}

edmd_once() { # dir -> "collisions seconds rss cpu_seconds"
    local t0 t1 col
    t0=$(date +%s.%N)
    # shellcheck disable=SC2046
    (cd "$1" && timed $(pinned) ./md >run.log 2>&1)
    t1=$(date +%s.%N)
    col=$(sed -n 's/^Simtime: .*Collisions: \([0-9]*\),.*/\1/p' "$1/run.log" | tail -1)
    # no count (a run that failed, or printed no line): a word that run_edmd refuses (the
    # fields must not shift: until 2026-12-01 the wall time was read as the count, and the
    # difference's arithmetic error ended the loop, a partial table, exit 0)
    echo "${col:-none} $(minus "$t0" "$t1") $(rss_of) $(cpu_of)"
}

run_edmd() { # n phi rep [pair]: EDMD's set-up run (to 0.1) and measured run (to 0.1 + S);
    # with pair, the measured run and nbep's one-thread run at once, each held to one of
    # CPU_A and CPU_B, which they swap each repeat (PAIRED)
    local S e1 e2 ca="" cb="" pn=""
    S=$(stretch "$1" "$2")
    e1=$(edmd_build "$1" "$2" 0.1) || return 1
    e2=$(edmd_build "$1" "$2" "$(awk -v s="$S" 'BEGIN { print 0.1 + s }')") || return 1
    if [ -n "${4:-}" ]; then
        if [ $(($3 % 2)) = 1 ]; then ca=$CPU_A cb=$CPU_B; else ca=$CPU_B cb=$CPU_A; fi
    fi
    read -r c1 w1 _ u1 < <(PIN=$cb TIME_OUT="$TIME_OUT.edmd" edmd_once "$e1")
    if [ -n "${4:-}" ]; then
        PIN=$ca TIME_OUT="$TIME_OUT.nbep" run_nbep "$1" "$2" 1 "$3" &
        pn=$!
    fi
    read -r c2 w2 r2 u2 < <(PIN=$cb TIME_OUT="$TIME_OUT.edmd" edmd_once "$e2")
    if [ -n "$pn" ]; then wait "$pn" || return 1; fi
    if ! [[ $c1 =~ ^[0-9]+$ && $c2 =~ ^[0-9]+$ ]]; then
        echo "EDMD failed: $e1 or $e2 (its run.log)" >&2
        return 1
    fi
    echo "edmd,$1,$2,1,$3,$((c2 - c1)),$(minus "$w1" "$w2"),$r2,$(minus "$u1" "$u2")," >>"$rows"
}

for n in $NS; do
    for phi in $PHIS; do
        melt "$n" "$phi" || exit 1
    done
done

# ---- COUNT=1: cachegrind's counts instead of times -------------------------------------------
# The counted stretch is a fifteenth of the timed one (0.2 time units at phi 0.50, 0.8 at 0.30
# for N = 32000: 30 to 130 thousand collisions, a few minutes under cachegrind). nbep resumes the
# melt at T1 and runs to T1 + 0.05 and to T1 + 0.05 + stretch; EDMD runs from nbep's fluid to 0.1
# and to 0.1 + stretch, built for AVX2 at most (valgrind 3.19 decodes no AVX-512, which
# -march=native may emit). The difference of the two runs leaves out set-up, reading and writing.
if [ "${COUNT:-0}" = 1 ]; then
    command -v valgrind >/dev/null || { echo "COUNT=1 needs valgrind" >&2; exit 1; }
    l2=${CG_L2:-$(lscpu -C=NAME,ONE-SIZE,WAYS -B 2>/dev/null | awk '$1 == "L2" { print $2 "," $3 }')}
    [ -n "$l2" ] || l2=1048576,16
    cg() { # out.json cg.out CMD...: cachegrind's totals of CMD as "Ir D1mr+D1mw LLmr+LLmw"
        local o=$1 c=$2
        shift 2
        valgrind --tool=cachegrind --cache-sim=yes --D1=49152,12,64 --LL="$l2",64 \
            --cachegrind-out-file="$c" "$@" >"$o.log" 2>&1 || { echo "failed: $* ($o.log)" >&2; return 1; }
        awk '/^summary:/ { print $2, $6 + $9, $7 + $10 }' "$c"
    }
    crow="$OUT/counts.csv"
    echo "engine,n,phi,collisions,instructions,d1_misses,l2_misses" >"$crow"
    for n in $NS; do
        for phi in $PHIS; do
            S=$(awk -v s="$(stretch "$n" "$phi")" 'BEGIN { printf "%.6g", s / 15 }')
            declare -A got=()
            for k in 1 2; do
                te=$(awk -v t="$T1" -v s="$S" -v k="$k" -v dt="$DT" 'BEGIN { print t + dt + (k - 1) * s }')
                out="$OUT/count-$k.h5"
                d=$(deck "$n" "$phi" "$(steps_to "$te")" "$DT" 1 "$out" "$FIELDS" "$STEPS1")
                cp "$OUT/melt-$n-$phi.h5" "$out"
                c=$(cg "$OUT/count-nbep-$k" "$OUT/count-nbep-$k.cg" "$NBEP" run "$d" --resume "$out" \
                    --quiet --summary "$OUT/count-nbep-$k.json") || exit 1
                got[nbep$k]="$(summary_field collisions <"$OUT/count-nbep-$k.json") $c"
                if [ -n "$edmd_src" ]; then
                    e=$(edmd_build "$n" "$phi" "$(awk -v s="$S" -v k="$k" 'BEGIN { print 0.1 + (k - 1) * s }')" cg) || exit 1
                    c=$(cd "$e" && cg run cg.out ./md) || exit 1
                    got[edmd$k]="$(sed -n 's/^Simtime: .*Collisions: \([0-9]*\),.*/\1/p' "$e/run.log" | tail -1) $c"
                fi
            done
            for eng in nbep edmd; do
                [ -n "${got[${eng}1]:-}" ] || continue
                # collisions, instructions, L1d and L2 misses of the short (1) and long (2) run
                read -r c1 i1 d1 m1 <<<"${got[${eng}1]}"
                read -r c2 i2 d2 m2 <<<"${got[${eng}2]}"
                echo "$eng,$n,$phi,$((c2 - c1)),$((i2 - i1)),$((d2 - d1)),$((m2 - m1))" >>"$crow"
            done
            unset got
        done
    done
    "$PY" - "$crow" "$l2" <<'PYEOF'
import csv, sys
rows = list(csv.DictReader(open(sys.argv[1])))
print(f"\nPer collision, from cachegrind (L1d 48 kB; second level {sys.argv[2]} bytes,ways):")
print("| engine | N | phi | collisions counted | instructions | L1d misses | L2 misses |")
print("| --- | --- | --- | --- | --- | --- | --- |")
per = {}
for r in rows:
    c = int(r["collisions"])
    if c <= 0:
        continue
    f = [int(r[k]) / c for k in ("instructions", "d1_misses", "l2_misses")]
    per[(r["engine"], r["n"], r["phi"])] = f
    print(f"| {r['engine']} | {r['n']} | {r['phi']} | {c} | {f[0]:.0f} | {f[1]:.1f} | {f[2]:.1f} |")
for (eng, n, phi), f in sorted(per.items()):
    e = per.get(("edmd", n, phi))
    if eng == "nbep" and e:
        print(f"  N {n}, phi {phi}: nbep / EDMD: instructions {f[0] / e[0]:.2f}, "
              f"L1d misses {f[1] / e[1]:.2f}, L2 misses {f[2] / e[2]:.2f}")
PYEOF
    exit 0
fi

for rep in $(seq "$REPS"); do
    for n in $NS; do
        for phi in $PHIS; do
            # a run that fails ends the benchmark, exit 1 (until 2026-11-30 the table was
            # printed without it, exit 0: every nbep run failing left EDMD's rows alone)
            # PAIRED: EDMD first, with nbep's one-thread run beside its measured run
            pair=""
            if [ "$PAIRED" = 1 ] && [ -n "$edmd_src" ] && [[ " $THREADS " == *" 1 "* ]]; then
                pair=1
                run_edmd "$n" "$phi" "$rep" pair || exit 1
            fi
            for nt in $THREADS; do
                [ -n "$pair" ] && [ "$nt" = 1 ] && continue
                run_nbep "$n" "$phi" "$nt" "$rep" || exit 1
                if [ "$CEILING" = 1 ] && [ "$nt" -gt 1 ]; then run_apart "$n" "$phi" "$nt" "$rep" || exit 1; fi
            done
            if [ -n "$edmd_src" ] && [ -z "$pair" ]; then run_edmd "$n" "$phi" "$rep" || exit 1; fi
        done
    done
    echo "repeat $rep of $REPS done"
done

# medians over repeats, then the table and the ratios
"$PY" - "$rows" <<'PYEOF'
import csv, statistics, sys
rows = list(csv.DictReader(open(sys.argv[1])))
# CEILING's k runs at once (engine "apart") as one row a repeat: their rates added (the
# collisions summed, over the seconds that give that rate), the largest RSS, the CPU summed
apart = {}
for r in rows:
    if r["engine"] == "apart":
        apart.setdefault((r["n"], r["phi"], r["threads"], r["rep"]), []).append(r)
rows = [r for r in rows if r["engine"] != "apart"]
for (n, phi, k, rep), rs in sorted(apart.items()):
    if len(rs) != int(k) or any(float(r["seconds"] or 0) <= 0 or int(r["collisions"] or 0) <= 0
                                for r in rs):
        continue
    c = sum(int(r["collisions"]) for r in rs)
    rate = sum(int(r["collisions"]) / float(r["seconds"]) for r in rs)
    rows.append({"engine": "apart", "n": n, "phi": phi, "threads": k, "rep": rep,
                 "collisions": str(c), "seconds": repr(c / rate),
                 "rss_bytes": str(max(int(r["rss_bytes"] or 0) for r in rs)),
                 "cpu_seconds": repr(sum(float(r["cpu_seconds"] or 0) for r in rs)),
                 "handover_ns": ""})
groups = {}
for r in rows:
    if not r["collisions"] or not r["seconds"] or float(r["seconds"]) <= 0:
        continue
    groups.setdefault((r["engine"], int(r["n"]), r["phi"], int(r["threads"])), []).append(r)
med = {}
for key, rs in groups.items():
    rates = [int(r["collisions"]) / float(r["seconds"]) for r in rs]
    cpus = [int(r["collisions"]) / float(r["cpu_seconds"]) for r in rs
            if r.get("cpu_seconds") and float(r["cpu_seconds"]) > 0]
    rss = statistics.median(int(r["rss_bytes"] or 0) for r in rs)
    med[key] = (statistics.median(rates), min(rates), max(rates), rss, len(rs),
                statistics.median(cpus) if cpus else None)
print("\nEquilibrium fluid, collisions per second of wall time and of CPU time (user + system):")
print("medians (spread) of the repeats")
print("| engine | N | phi | threads | collisions/s (wall) | spread | collisions/CPU s | "
      "peak RSS / sphere | runs |")
print("| --- | --- | --- | --- | --- | --- | --- | --- | --- |")
for key in sorted(med):
    rate, lo, hi, rss, k, cpu = med[key]
    cpu_s = f"{cpu/1e3:.1f} k" if cpu else "-"
    print(f"| {key[0]} | {key[1]} | {key[2]} | {key[3]} | {rate/1e3:.1f} k | "
          f"{lo/1e3:.0f}-{hi/1e3:.0f} k | {cpu_s} | {rss/key[1]/1e3:.3f} kB | {k} |")
print("\nratios of medians (wall; CPU)")
for (eng, n, phi, nt), (rate, *_rest) in sorted(med.items()):
    if eng != "nbep":
        continue
    cpu = med[(eng, n, phi, nt)][5]
    e = med.get(("edmd", n, phi, 1))
    c1 = med.get(("nbep", n, phi, 1))
    parts = [f"N {n}, phi {phi}, {nt} thread(s)"]
    if e:
        r = f"nbep / EDMD = {rate / e[0]:.2f}"
        if cpu and e[5]:
            r += f"; by CPU time {cpu / e[5]:.2f}"
        parts.append(r)
    if c1 and nt != 1:
        parts.append(f"{nt} threads / 1 thread = {rate / c1[0]:.2f}")
    a = med.get(("apart", n, phi, nt))
    if a and c1:
        parts.append(f"{nt} one-thread runs at once / 1 thread = {a[0] / c1[0]:.2f} (the "
                     f"machine's ceiling), {nt} threads / that = {rate / a[0]:.2f}")
    print("  " + "; ".join(parts))

# each repeat's one-thread rate over the same repeat's EDMD rate (with PAIRED=1, the two ran
# at once), and their median
one = {(r["n"], r["phi"], r["rep"]): r for r in rows if r["engine"] == "nbep" and r["threads"] == "1"}
rate = lambda r: int(r["collisions"]) / float(r["seconds"])
edmd = {(r["n"], r["phi"], r["rep"]): r for r in rows if r["engine"] == "edmd"
        and float(r["seconds"] or 0) > 0}
if edmd:
    print("\nper repeat: nbep, 1 thread / EDMD (median of the repeats' own ratios)")
    for n, phi in sorted({(k[1], k[2]) for k in groups if k[0] == "nbep" and k[3] == 1}):
        rs = [rate(one[k]) / rate(edmd[k]) for k in sorted(one, key=lambda k: int(k[2]))
              if k[:2] == (str(n), phi) and k in edmd and float(one[k]["seconds"]) > 0]
        if rs:
            print(f"  N {n}, phi {phi}: " + ", ".join(f"{x:.2f}" for x in rs) +
                  f" (median {statistics.median(rs):.2f})")

# each repeat's multi-thread rate over the same repeat's one-thread rate, with the cores'
# hand-over time (ns, before and after the run)
multi = sorted(k for k in groups if k[0] == "nbep" and k[3] != 1)
if multi:
    print("\nper repeat: threads / 1 thread (hand-over ns before, after; with CEILING, the "
          "same repeat's runs at once / 1 thread)")
for key in multi:
    parts = []
    for r in sorted(groups[key], key=lambda r: int(r["rep"])):
        o = one.get((r["n"], r["phi"], r["rep"]))
        if not o or float(o["seconds"]) <= 0:
            continue
        ratio = (int(r["collisions"]) / float(r["seconds"])) / (int(o["collisions"]) / float(o["seconds"]))
        ho = ", ".join(r.get("handover_ns", "").split())
        ap = [x for x in groups.get(("apart",) + key[1:], []) if x["rep"] == r["rep"]]
        if ap:  # CEILING: the same repeat's runs at once over its one-thread run
            ceil = (int(ap[0]["collisions"]) / float(ap[0]["seconds"])) / (int(o["collisions"]) / float(o["seconds"]))
            ho = (ho + "; " if ho else "") + f"runs at once {ceil:.2f}"
        parts.append(f"{ratio:.2f} ({ho})" if ho else f"{ratio:.2f}")
    print(f"  N {key[1]}, phi {key[2]}, {key[3]} threads: " + "; ".join(parts))
PYEOF
