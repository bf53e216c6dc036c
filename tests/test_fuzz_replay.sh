#!/usr/bin/env bash
# The deck parser's fuzz harness (tests/fuzz/fuzz_scene.c) on every deck the project keeps
# (inputs/, tests/data/, the fuzzer's past findings among them) and on copies of the examples
# with overrides after "#@set" (as scripts/fuzz.sh seeds them): each load keeps the harness's
# contract, and the harness links from tests/fuzz/sources, the list scripts/fuzz.sh builds from
# (build/tests/fuzz_replay, made by make check).
. "$(dirname "$0")/lib.sh"
bin=build/tests/fuzz_replay
[ -x "$bin" ] || { echo "FAIL $bin missing: make check builds it"; exit 1; }
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
for d in inputs/*.deck; do
    { cat "$d"; printf '%s\n' '#@set' 'run.steps=5' 'spheres.[0].radius=abc' \
        'physics.gravity=[0,0,-1]' 'no.such=1'; } >"$tmp/set-$(basename "$d")"
done
decks=(inputs/*.deck tests/data/*.deck "$tmp"/set-*.deck)
if NBEP_FUZZ_TMP=$tmp timeout -k 5 120 "$bin" "${decks[@]}" >"$tmp/out" 2>&1 &&
    grep -qx "fuzz_replay: ${#decks[@]} inputs kept the harness's contract" "$tmp/out"; then
    echo "ok   the fuzz harness keeps its contract on ${#decks[@]} decks"
else
    echo "FAIL the fuzz harness on ${#decks[@]} decks: $(tail -n 3 "$tmp/out")"
    exit 1
fi
