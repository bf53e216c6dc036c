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
# what it runs, through a stand-in nbep that logs each run's deck, NBEP_SCHEDULED and allowed
# CPUs, then runs bin/nbep; FAKE=fail fails the scheduled half on CPU 1, FAKE=differ adds one
# to that run's collisions
real=$(cd bin && pwd)/nbep
abs=$(cd "$tmp" && pwd) # (the script works in its own folder)
cat >"$abs/nbep" <<FAKE
#!/usr/bin/env bash
deck=\$2 sum=
for ((k = 1; k <= \$#; k++)); do [ "\${!k}" = --summary ] && { k=\$((k + 1)); sum=\${!k}; }; done
cpus=\$(sed -n 's/^Cpus_allowed_list:[[:space:]]*//p' /proc/self/status)
echo "\$(basename "\$deck") \${NBEP_SCHEDULED:-plain} \$cpus" >>"$abs/log.txt"
if [ "\${FAKE:-}" = fail ] && [ "\${NBEP_SCHEDULED:-}" = 1 ] && [ "\$cpus" = 1 ]; then exit 1; fi
"$real" "\$@" || exit
if [ "\${FAKE:-}" = differ ] && [ "\${NBEP_SCHEDULED:-}" = 1 ] && [ "\$cpus" = 1 ]; then
    "$PY" -c "import json, sys; d = json.load(open(sys.argv[1])); d['collisions'] += 1; json.dump(d, open(sys.argv[1], 'w'))" "\$sum"
fi
FAKE
chmod +x "$abs/nbep"
mkdir -p "$abs/t"
rm -f "$abs/log.txt"
TMPDIR="$abs/t" KEEP=1 NBEP_SCHEDULED=1 NBEP="$abs/nbep" timeout 120 env PYTHON="$PY" \
    bash scripts/bench-halves.sh 1 2000 0.25 >"$abs/out.txt" 2>&1
rc=$?
kept=$(sed -n 's/^kept: //p' "$abs/out.txt")
check "through the stand-in (NBEP_SCHEDULED=1 in the caller's environment): exit 0 (got $rc)" "[ $rc = 0 ]"
check "the runs: the full fluid alone on CPU 0 then 1, the halves plain on both, then scheduled on both (the plain ones without NBEP_SCHEDULED)" \
    "[ \"\$(grep -v melt '$abs/log.txt' | sort | tr '\n' ' ')\" = 'full.deck plain 0 full.deck plain 1 half.deck 1 0 half.deck 1 1 half.deck plain 0 half.deck plain 1 ' ]"
check "the decks: the full box and the half at packing fraction 0.25, melts of 20 steps, runs to 30" \
    "\"\$PY\" -c '
import math, re, sys
d = sys.argv[1]
for name, n, steps in ((\"full-melt\", 2000, 20), (\"full\", 2000, 30), (\"half-melt\", 1000, 20), (\"half\", 1000, 30)):
    t = open(d + \"/\" + name + \".deck\").read()
    side = float(re.search(r\"max = \\[([0-9.e+-]+),\", t).group(1))
    assert abs(n * math.pi / 6 / side ** 3 - 0.25) < 1e-12, (name, side)
    assert re.search(r\"count = %d;\" % n, t) and re.search(r\"steps = %d;\" % steps, t), name' '$kept'"
rm -rf "$abs/t"
for fake in fail differ; do
    mkdir -p "$abs/t"
    FAKE=$fake TMPDIR="$abs/t" NBEP="$abs/nbep" timeout 120 env PYTHON="$PY" \
        bash scripts/bench-halves.sh 1 2000 0.30 >"$abs/out.txt" 2>"$abs/err.txt"
    rc=$?
    check "a scheduled half that $( [ $fake = fail ] && echo fails || echo counts other collisions ): exit 1 (got $rc), said, its temporary folder gone" \
        "[ $rc = 1 ] && grep -q 'bench-halves.sh: the' '$abs/err.txt' && [ -z \"\$(ls -A '$abs/t')\" ]"
    rm -rf "$abs/t"
done
test_end bench_halves
