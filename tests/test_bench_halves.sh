#!/usr/bin/env bash
# scripts/bench-halves.sh, two half fluids at once against the full one alone (README,
# Benchmarks: Threads on dense scenes): on a small fluid, one repeat, it prints a row and the
# medians, the halves' box side is the full one's over the cube root of 2 (the same packing
# fraction), every half run (plain and scheduled, on either CPU) has the same collisions, and
# the row's two figures are the full run's mean time over the slower half's, recomputed here
# from the times it lists; bad arguments are refused with one line and exit 2, --help exits 0.
# Needs two CPUs and taskset (the script's own need): else skipped.
# Run from anywhere; exit status 1 when a check fails.
. "$(dirname "$0")/lib.sh"
test_tmp bench_halves
[ -x bin/nbep ] || { echo "FAIL bin/nbep not built"; exit 1; }
timeout 20 bash scripts/bench-halves.sh --help >"$tmp/out.txt" 2>&1
rc=$?
check "--help: exit 0 (got $rc), the usage line" "[ $rc = 0 ] && grep -q '^usage: scripts/bench-halves.sh' '$tmp/out.txt'"
for args in "2 2001" "0 2000" "2 2000 0.6" "1 2 3 4" "x"; do
    timeout 20 bash scripts/bench-halves.sh $args >"$tmp/out.txt" 2>"$tmp/err.txt"
    rc=$?
    check "bench-halves.sh $args: exit 2 (got $rc), one line, nothing run" \
        "[ $rc = 2 ] && [ \$(wc -l <'$tmp/err.txt') = 1 ] && [ ! -s '$tmp/out.txt' ]"
done
if ! command -v taskset >/dev/null || ! taskset -c 0 true 2>/dev/null ||
    ! taskset -c 1 true 2>/dev/null; then
    echo "skipped: bench-halves.sh runs on CPUs 0 and 1 (taskset), which this process may not use"
    test_end bench_halves
    exit 77
fi
timeout 120 env PYTHON="$PY" bash scripts/bench-halves.sh 1 2000 0.30 >"$tmp/out.txt" 2>&1
rc=$?
cat "$tmp/out.txt"
check "bench-halves.sh 1 2000 0.30: exit 0 (got $rc)" "[ $rc = 0 ]"
check "the halves' collisions the same in every run" \
    "grep -q \"the halves' collisions the same in every run: True\" '$tmp/out.txt'"
check "the halves' side is the full box's over the cube root of 2; the row's figures its times' ratios" \
    "\"\$PY\" -c '
import re, sys
t = open(sys.argv[1]).read()
lf, lh = map(float, re.search(r\"box side ([0-9.]+); halves: N = 1000, side ([0-9.]+)\", t).groups())
assert abs(lh * 2 ** (1 / 3) - lf) <= 1e-12 * lf, (lf, lh)
row = re.search(r\"^ +1 +(.*)$\", t, re.M).group(1).split()
f0, f1, p0, p1, s0, s1, rp, rs = map(float, row)
full = (f0 + f1) / 2
# (each time printed to 4 decimals, 0.00005 off at most, each figure to 3)
for r, a, b in ((rp, p0, p1), (rs, s0, s1)):
    want = full / max(a, b)
    assert abs(r - want) <= want * (0.00005 / full + 0.00005 / max(a, b)) + 0.0005, (r, want)
m = re.search(r\"plain halves ([0-9.]+) .* scheduled halves ([0-9.]+) \", t)
assert float(m.group(1)) == rp and float(m.group(2)) == rs, (m.groups(), rp, rs)' '$tmp/out.txt'"
test_end bench_halves
