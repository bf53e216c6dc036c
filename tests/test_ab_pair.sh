#!/usr/bin/env bash
# scripts/ab-pair.sh, the paired A/B timing of two builds (README, Benchmarks: How to
# reproduce): on a tiny fluid with the same binary as A and B, every repeat's collisions agree,
# and the figure over each two repeats (the cores swapped between them) is the geometric mean
# of their two ratios, recomputed here from the ratios it lists; an odd last repeat stays out
# of it. Needs two CPUs and taskset (the script's own need): else skipped.
# Run from anywhere; exit status 1 when a check fails.
. "$(dirname "$0")/lib.sh"
test_tmp ab_pair
need_py h5py
[ -x bin/nbep ] || { echo "FAIL bin/nbep not built"; exit 1; }
if ! command -v taskset >/dev/null || ! taskset -c 0 true 2>/dev/null ||
    ! taskset -c 1 true 2>/dev/null; then
    echo "skipped: ab-pair.sh runs on CPUs 0 and 1 (taskset), which this process may not use"
    exit 77
fi
# 500 spheres at phi = 0.30 in a periodic box (side 9.42), 10 steps of 0.02: well under a second
cat >"$tmp/fluid.deck" <<'DECK'
run: { algorithm = "predictive"; steps = 10; dt = 0.02; threads = 1; seed = 3; neighbors = "cells"; };
box: { min = [0.0, 0.0, 0.0]; max = [9.42, 9.42, 9.42]; periodic = [true, true, true]; };
spheres = ( { count = 500; radius = 0.5; mass = 1.0; place = "lattice"; speed = 1.7320508075688772; } );
output: { file = "fluid.h5"; every = 10; fields = ["position"]; };
DECK
timeout 120 bash scripts/ab-pair.sh 3 "$tmp/fluid.deck" bin/nbep bin/nbep >"$tmp/out.txt" 2>&1
rc=$?
cat "$tmp/out.txt"
check "ab-pair.sh, 3 repeats of one binary against itself: exit 0 (got $rc)" "[ $rc = 0 ]"
check "the same collisions in every repeat" "grep -q 'same collisions: True' '$tmp/out.txt'"
check "the pairs' figure: one pair of 3 repeats, the geometric mean of the first two ratios" \
    "\"\$PY\" -c '
import re, sys
t = open(sys.argv[1]).read()
r = [float(x) for x in re.search(r\"B/A median [0-9.]+ \\[([0-9. ]+)\\]\", t).group(1).split()]
m = re.search(r\"cores swapped \\(geometric mean\\): median ([0-9.]+) \\[([0-9. ]+)\\]\", t)
p = [float(x) for x in m.group(2).split()]
assert len(r) == 3 and len(p) == 1, (r, p)
# (relative: the ratios are printed to 3 decimals, each 0.0005 off at most)
g = (r[0] * r[1]) ** 0.5
assert abs(p[0] - g) <= 0.0006 * g * (1 / r[0] + 1 / r[1]) + 0.0005 and float(m.group(1)) == p[0], (r, p)' '$tmp/out.txt'"
test_end ab_pair
