#!/usr/bin/env bash
# SIGTERM and SIGINT (a batch job at its time limit, or Ctrl-C) finish the current step,
# write its frame, close the file and exit 143 or 130; the file opens with every frame.
set -u
cd "$(dirname "$0")/.."
tmp=build/tests/tmp/signals
rm -rf "$tmp" && mkdir -p "$tmp"
fail=0
check() { if eval "$2"; then echo "ok   $1"; else echo "FAIL $1"; fail=1; fi; }

for sig in TERM INT; do
    want=$([ $sig = TERM ] && echo 143 || echo 130)
    out=$tmp/run-$sig.h5
    # a run far too long to finish: it can only end by the signal
    bin/nbep run inputs/paper-box.deck --quiet -n 100000000 --set spheres.[0].count=512 \
        -o "$out" --summary "$tmp/summary-$sig.json" 2>"$tmp/stderr-$sig" &
    pid=$!
    # the output file is created after the deck is read and before the first step; signal
    # handlers are installed before either (bounded wait, 30 s at most)
    for _ in $(seq 300); do [ -s "$out" ] && break; sleep 0.1; done
    sleep 0.3
    kill -$sig $pid
    wait $pid
    rc=$?
    check "SIG$sig exits $want (got $rc)" "[ $rc = $want ]"
    check "SIG$sig leaves a readable file with frames" \
        "bin/nbep info '$out' > '$tmp/info-$sig' && grep -q '^frames: *[1-9]' '$tmp/info-$sig'"
    check "SIG$sig file holds the summary of the steps done" \
        "grep -q '\"steps\": [1-9]' '$tmp/info-$sig'"
    check "SIG$sig writes the JSON summary" "grep -q nbep-summary-1 '$tmp/summary-$sig.json'"
    check "SIG$sig says so on stderr" "grep -q 'stopped after' '$tmp/stderr-$sig' || grep -qi 'interrupt\\|terminat' '$tmp/stderr-$sig'"
    lines=$(wc -l < "$tmp/stderr-$sig")
    check "SIG$sig: that is the only line on stderr (got $lines)" "[ $lines = 1 ]"
done
[ $fail = 0 ] && echo "signals: all passed"
exit $fail
