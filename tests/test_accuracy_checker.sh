#!/usr/bin/env bash
# scripts/accuracy.py's missed-collision checker (make accuracy's `missed` column), by its own
# self-test: spheres given to pass through each other within one step at dt = 1e-2, in open
# space (head-on, grazing, the quartic's unequal accelerations, a near miss that is no contact)
# and across the faces of a periodic box (the pair measured by its nearest images: until
# 2026-12-05 the checker took the wrapped positions as they are and missed such a miss, a
# review's find). naive and seminaive miss exactly the planted pairs; predictive misses none
# and leaves no overlap unresolved.
# Run from anywhere after `make`; exit status 1 when a check fails.
. "$(dirname "$0")/lib.sh"
test_tmp accuracy_checker
need_py h5py numpy
"$PY" scripts/accuracy.py selftest --nbep bin/nbep >"$tmp/out.txt" 2>"$tmp/err.txt"
rc=$?
check "accuracy.py selftest: exit 0 (got $rc): $(tr '\n' ';' <"$tmp/out.txt" | head -c 600) $(head -c 300 "$tmp/err.txt")" \
    "[ $rc = 0 ]"
for line in "selftest: naive: missed 3 (want 3)" "selftest: predictive: missed 0 (want 0)" \
            "selftest: periodic naive: missed 2 (want 2), responses 0, pairs \[\[0, 1\], \[2, 3\]\]" \
            "selftest: periodic predictive: missed 0 (want 0)"; do
    check "... it says: $line" "grep -q '^$line' '$tmp/out.txt'"
done
test_end accuracy_checker
