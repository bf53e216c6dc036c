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

test_end bench_dense
