#!/usr/bin/env bash
# make bench-dense's nbep side on a tiny fluid (README, Benchmarks: Dense fluids): the melt and
# the timed runs that resume it succeed and give the table a row of collisions a second, for
# one thread and the team of two; an nbep run that fails ends the benchmark with exit 1. Until
# 2026-11-30 every timed run failed (a resume refuses a deck with other output.fields than
# the file's, and the timed deck asked for none) and the script printed EDMD's rows alone,
# exit 0. EDMD is left out (EDMD_DIR unset): its checkout is no part of the tree.
# Run from anywhere; exit status 1 when a check fails.
. "$(dirname "$0")/lib.sh"
test_tmp bench_dense
need_py h5py
[ -x bin/nbep ] || { echo "FAIL bin/nbep not built"; exit 1; }
# 500 spheres (a side of 9.5 at phi = 0.30, 7.1 at 0.50: three cells across), a stretch of
# 192 * 0.002 * 4 = 1.5 time units at phi = 0.30: about 8000 collisions, well under a second
export NS=500 PHIS="0.30 0.50" THREADS="1 2" REPS=1 SCALE=0.002
unset EDMD_DIR COUNT

OUT="$tmp/good" timeout 120 bash scripts/bench-dense.sh >"$tmp/good.txt" 2>&1
rc=$?
check "bench-dense.sh on 500 spheres: exit 0 (got $rc), no nbep failure" \
    "[ $rc = 0 ] && ! grep -q 'nbep failed' '$tmp/good.txt'"
for phi in 0.30 0.50; do
    for nt in 1 2; do
        check "a table row for nbep, phi $phi, $nt thread(s), with collisions a second" \
            "grep -q '^| nbep | 500 | $phi | $nt | [0-9.]* k |' '$tmp/good.txt'"
        check "its raw row: collisions and seconds above 0" \
            "awk -F, '\$1 == \"nbep\" && \$3 == \"$phi\" && \$4 == \"$nt\" && \$6 > 0 && \$7 > 0 { ok = 1 } END { exit !ok }' '$tmp/good/rows.csv'"
    done
done

# a row counts the collisions of the stretch timed, since the melt's frame, not the melt's too
# (a resumed run's summary counts from step 0 since 2026-11-30): the last run's row (phi 0.50,
# 2 threads) is its file's totals at its end less those at the frame it resumed
check "the row's collisions are the stretch's own, the melt's taken off" \
    "\"\$PY\" -c '
import csv, h5py, sys
row = [r for r in csv.reader(open(sys.argv[1])) if r[0] == \"nbep\"][-1]
t = h5py.File(sys.argv[2], \"r\")[\"frames/totals\"]
c = lambda k: int(t[k][\"sphere_collisions\"]) + int(t[k][\"plane_collisions\"])
assert int(row[5]) == c(-1) - c(-2) > 0, (row, c(-1), c(-2))' '$tmp/good/rows.csv' '$tmp/good/run.h5'"

# an nbep that melts the fluid but fails each resumed run: the benchmark stops, exit 1
cat >"$tmp/nbep-fails-resume" <<EOF
#!/bin/sh
for a in "\$@"; do [ "\$a" = --resume ] && { echo "nbep: made to fail" >&2; exit 1; }; done
exec "$PWD/bin/nbep" "\$@"
EOF
chmod +x "$tmp/nbep-fails-resume"
NBEP="$tmp/nbep-fails-resume" OUT="$tmp/bad" timeout 120 bash scripts/bench-dense.sh \
    >"$tmp/bad.txt" 2>&1
rc=$?
check "a timed nbep run that fails: exit 1 (got $rc), its deck named, no table" \
    "[ $rc = 1 ] && grep -q '^nbep failed: ' '$tmp/bad.txt' && ! grep -q '^| engine' '$tmp/bad.txt'"

# PAIRED=1 (2026-12-01): nbep's one-thread run and EDMD's measured run at once, each held to
# one of the first two CPUs the process may use, swapped each repeat (skipped where it may use
# one: then it is refused, the last check). EDMD is a stand-in here (its checkout is no part of
# the tree): a Single/ folder whose mdSingle.c has the globals the script sets and prints the
# line it reads, 10^5 collisions a time unit, after a wait of a time unit's tenth of a second;
# it and an nbep wrapper note the CPUs they may run on.
mkdir -p "$tmp/edmd/Single"
cat >"$tmp/edmd/Single/mdSingle.c" <<'EOF2'
#define _GNU_SOURCE
#include <sched.h>
#include <stdio.h>
#include <stdlib.h>
#include <time.h>
double maxtime = 100;
double writeinterval = 1;
double snapshotinterval = 1;
int initialconfig = 1;
const int usethermostat = 1;
int main(void)
{
    cpu_set_t s;
    FILE *f = fopen(getenv("CPU_LOG"), "a");
    if (f && sched_getaffinity(0, sizeof s, &s) == 0) {
        fprintf(f, "edmd %g:", maxtime);
        for (int c = 0; c < 64; c++)
            if (CPU_ISSET(c, &s))
                fprintf(f, " %d", c);
        fprintf(f, "\n");
        fclose(f);
    }
    /* EDMD_FAIL_PAST set: a run past the set-up's time fails, printing no collision line */
    if (getenv("EDMD_FAIL_PAST") && maxtime > 1)
        return 1;
    struct timespec w = {0, (long)(maxtime * 1e8)};
    nanosleep(&w, NULL);
    printf("Simtime: %g, Collisions: %ld, Walls: 0\n", maxtime, (long)(maxtime * 1e5));
    return 0;
}
EOF2
printf 'md: mdSingle.c\n\tcc -O2 -march=native -o md mdSingle.c\n' >"$tmp/edmd/Single/Makefile"
cat >"$tmp/nbep-cpus" <<EOF2
#!/bin/sh
for a in "\$@"; do [ "\$a" = --resume ] && echo "nbep \$(grep Cpus_allowed_list /proc/self/status | cut -f2)" >>"$PWD/$tmp/cpus.log"; done
exec "$PWD/bin/nbep" "\$@"
EOF2
chmod +x "$tmp/nbep-cpus"
read -r a b < <("$PY" -c 'import os; print(*sorted(os.sched_getaffinity(0))[:2])')
free=$(sed -n 's/^Cpus_allowed_list:[[:space:]]*//p' /proc/self/status)
if [ -z "$b" ]; then
    echo "skip PAIRED=1 runs: this test may use one CPU ($a)"
else
    CPU_LOG="$PWD/$tmp/cpus.log" PAIRED=1 EDMD_DIR="$tmp/edmd" NBEP="$tmp/nbep-cpus" PHIS=0.30 REPS=2 \
        OUT="$tmp/paired" timeout 120 bash scripts/bench-dense.sh >"$tmp/paired.txt" 2>&1
    rc=$?
    check "PAIRED=1 with a stand-in EDMD: exit 0 (got $rc), rows for EDMD and nbep on 1 and 2 threads" \
        "[ $rc = 0 ] && grep -q '^| edmd | 500 | 0.30 | 1 | [0-9.]* k |' '$tmp/paired.txt' &&
         grep -q '^| nbep | 500 | 0.30 | 1 | [0-9.]* k |' '$tmp/paired.txt' &&
         grep -q '^| nbep | 500 | 0.30 | 2 | [0-9.]* k |' '$tmp/paired.txt'"
    # (the stretch at phi = 0.30: 4 * 96000 / 500 * SCALE = 1.536 time units, 153600 collisions)
    check "PAIRED=1: EDMD's row is its measured run less its set-up run (the stretch's 10^5 a time unit)" \
        "awk -F, '\$1 == \"edmd\" { n++; ok += \$6 == 153600 } END { exit !(n == 2 && ok == 2) }' '$tmp/paired/rows.csv'"
    check "PAIRED=1: each repeat's own ratio of nbep on one thread to EDMD, and their median" \
        "grep -Eq '^  N 500, phi 0.30: [0-9.]+, [0-9.]+ \\(median [0-9.]+\\)\$' '$tmp/paired.txt'"
    # repeat 1: nbep on the first CPU this test may use (a and b above: 0 and 1 on a machine of
    # its own, others in a job's cpuset; until 2026-12-01 the script took 0 and 1 whatever it was
    # given) and EDMD's runs on the second, repeat 2 the other way; the two-thread runs as given
    check "PAIRED=1: nbep's one-thread run and EDMD's runs held to CPUs $a and $b, swapped each repeat, the two-thread runs on $free as given" \
        "tr '\\n' '|' <'$tmp/cpus.log' | grep -Eq '^edmd 0.1: $b\\|(nbep $a|edmd 1.636: $b)\\|(nbep $a|edmd 1.636: $b)\\|nbep $free\\|edmd 0.1: $a\\|(nbep $b|edmd 1.636: $a)\\|(nbep $b|edmd 1.636: $a)\\|nbep $free\\|\$'"
fi

# CEILING=1 (2026-12-07): beside the two-thread run, two one-thread runs of the same stretch at
# once, held to the first two CPUs the test may use, their rates added in an "apart" row, and
# the ratios say what share of that the two threads got
if [ -n "$b" ]; then
    : >"$tmp/cpus.log"
    CEILING=1 NBEP="$tmp/nbep-cpus" PHIS=0.30 REPS=2 OUT="$tmp/ceiling" timeout 120 \
        bash scripts/bench-dense.sh >"$tmp/ceiling.txt" 2>&1
    rc=$?
    check "CEILING=1: exit 0 (got $rc), a table row 'apart' for 2 runs at once beside nbep's 1 and 2 threads" \
        "[ $rc = 0 ] && grep -q '^| apart | 500 | 0.30 | 2 | [0-9.]* k |' '$tmp/ceiling.txt' &&
         grep -q '^| nbep | 500 | 0.30 | 2 | [0-9.]* k |' '$tmp/ceiling.txt'"
    check "CEILING=1: two raw rows a repeat, each the stretch's own collisions (the one-thread run's)" \
        "awk -F, '\$1 == \"nbep\" && \$4 == 1 { one[\$5] = \$6 } \$1 == \"apart\" { n[\$5]++; ok[\$5] += \$4 == 2 && \$7 > 0 && \$6 == one[\$5] }
                  END { exit !(n[1] == 2 && ok[1] == 2 && n[2] == 2 && ok[2] == 2) }' '$tmp/ceiling/rows.csv'"
    check "CEILING=1: the ceiling's ratio and the two threads' share of it, and each repeat's" \
        "grep -Eq '2 one-thread runs at once / 1 thread = [0-9.]+ \\(the machine.s ceiling\\), 2 threads / that = [0-9.]+\$' '$tmp/ceiling.txt' &&
         grep -Eq '^  N 500, phi 0.30, 2 threads: [0-9.]+ \\([^)]*runs at once [0-9.]+\\); [0-9.]+ \\([^)]*runs at once [0-9.]+\\)\$' '$tmp/ceiling.txt'"
    check "CEILING=1: the ceiling is the runs at once's added rates over the one thread's (medians of the raw rows)" \
        "\"\$PY\" -c '
import csv, re, statistics as st, sys
rows = list(csv.DictReader(open(sys.argv[1])))
rate = lambda r: int(r[\"collisions\"]) / float(r[\"seconds\"])
one = st.median(rate(r) for r in rows if r[\"engine\"] == \"nbep\" and r[\"threads\"] == \"1\")
two = st.median(rate(r) for r in rows if r[\"engine\"] == \"nbep\" and r[\"threads\"] == \"2\")
at_once = st.median(sum(rate(r) for r in rows if r[\"engine\"] == \"apart\" and r[\"rep\"] == k) for k in (\"1\", \"2\"))
m = re.search(r\"at once / 1 thread = ([0-9.]+) .*, 2 threads / that = ([0-9.]+)\", open(sys.argv[2]).read())
assert m and abs(float(m[1]) - at_once / one) < 0.006 and abs(float(m[2]) - two / at_once) < 0.006, (m and m.groups(), at_once / one, two / at_once)
' '$tmp/ceiling/rows.csv' '$tmp/ceiling.txt'"
    check "CEILING=1: the runs at once held to CPUs $a and $b, one each; the others on $free as given" \
        "[ \"\$(sort '$tmp/cpus.log' | uniq -c | awk '{ printf \"%s:%s \", \$1, \$3 }')\" = \"\$(printf '2 nbep %s\\n2 nbep %s\\n4 nbep %s\\n' '$a' '$b' '$free' | sort -k3 | awk '{ printf \"%s:%s \", \$1, \$3 }')\" ]"
fi

# an EDMD whose measured run fails (no collision line): the benchmark stops, exit 1, EDMD named
# (run apart, not paired: the same read of its count)
# (until 2026-12-01 the wall time was read as its count, bash's arithmetic error ended the
# loop after one repeat, and the script printed a partial table with exit 0)
CPU_LOG=/dev/null EDMD_FAIL_PAST=1 EDMD_DIR="$tmp/edmd" PHIS=0.30 REPS=2 \
    THREADS=1 OUT="$tmp/edmd-fails" timeout 120 bash scripts/bench-dense.sh >"$tmp/edmd-fails.txt" 2>&1
rc=$?
check "an EDMD run that fails: exit 1 (got $rc), 'EDMD failed' said, no table" \
    "[ $rc = 1 ] && grep -q '^EDMD failed: ' '$tmp/edmd-fails.txt' && ! grep -q '^| engine' '$tmp/edmd-fails.txt'"

# PAIRED=1 where this process may use one CPU: refused before anything runs, exit 2
taskset -c "$a" env PAIRED=1 EDMD_DIR="$tmp/edmd" PHIS=0.30 REPS=1 OUT="$tmp/one-cpu" \
    timeout 60 bash scripts/bench-dense.sh >"$tmp/one-cpu.txt" 2>&1
rc=$?
check "PAIRED=1 on one CPU: exit 2 (got $rc), one line that says why, nothing run" \
    "[ $rc = 2 ] && grep -q 'PAIRED=1 needs two CPUs' '$tmp/one-cpu.txt' && [ ! -e '$tmp/one-cpu/rows.csv' ]"

# CEILING=1 asking for more CPUs than this process may use: refused before anything runs, exit 2
taskset -c "$a" env CEILING=1 PHIS=0.30 REPS=1 OUT="$tmp/one-cpu-ceiling" \
    timeout 60 bash scripts/bench-dense.sh >"$tmp/one-cpu-ceiling.txt" 2>&1
rc=$?
check "CEILING=1 with THREADS up to 2 on one CPU: exit 2 (got $rc), one line that says why, nothing run" \
    "[ $rc = 2 ] && grep -q 'CEILING=1 needs 2 CPUs' '$tmp/one-cpu-ceiling.txt' && [ ! -e '$tmp/one-cpu-ceiling/rows.csv' ]"

test_end bench_dense
