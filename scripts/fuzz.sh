#!/usr/bin/env bash
# Fuzzes the deck parser (nbep_scene_load, --set overrides included) with libFuzzer under
# AddressSanitizer, UndefinedBehaviorSanitizer and LeakSanitizer for a bounded time, then
# reports every input that crashed, leaked, hung or ran out of memory.
#
#   scripts/fuzz.sh [SECONDS] [JOBS]        default: 60 s, 1 job (parallel fuzzing processes)
#
# It builds build/fuzz/fuzz_scene from tests/fuzz/fuzz_scene.c and the parser's sources with
# clang (installing clang and its fuzzer runtime through apt-get when they are missing),
# seeds a corpus from inputs/*.deck and tests/data/*.deck (and copies of some with --set
# overrides appended, see the harness), keeps what it learns in build/fuzz/corpus/ for the
# next run, and saves findings in build/fuzz/artifacts/ with the first lines of each report.
# Reproduce one with: build/fuzz/fuzz_scene build/fuzz/artifacts/crash-...
#
# Exit status: 0 nothing found, 1 findings, 2 bad usage or the build failed.
# CI does not run this (it takes minutes and clang); run it by hand after touching the parser.
set -euo pipefail

usage() { echo "usage: scripts/fuzz.sh [SECONDS] [JOBS]" >&2; exit 2; }
seconds=${1:-60}
jobs=${2:-1}
[[ $seconds =~ ^[0-9]+$ && $seconds -gt 0 ]] || usage
[[ $jobs =~ ^[0-9]+$ && $jobs -gt 0 ]] || usage
[ $# -le 2 ] || usage

cd "$(dirname "$0")/.."
out=build/fuzz
obj=$out/obj
mkdir -p "$obj" "$out/corpus" "$out/artifacts" "$out/tmp"

# ---- the toolchain: clang with libFuzzer's runtime ------------------------------------------
# True when clang can link a libFuzzer target with the sanitizers.
fuzzer_links() {
    command -v clang >/dev/null 2>&1 || return 1
    printf '%s\n' 'int LLVMFuzzerTestOneInput(const unsigned char *d, unsigned long n)' \
        '{ (void)d; (void)n; return 0; }' >"$out/tmp/probe.c"
    clang -fsanitize=fuzzer,address,undefined "$out/tmp/probe.c" -o "$out/tmp/probe" \
        >/dev/null 2>&1
}

# apt-get install, as root or through sudo; apt-get update first only when that fails.
apt_install() {
    local as_root=()
    if [ "$(id -u)" -ne 0 ]; then
        if ! command -v sudo >/dev/null 2>&1; then
            echo "fuzz.sh: need root or sudo to install $*" >&2
            return 1
        fi
        as_root=(sudo)
    fi
    echo "fuzz.sh: installing $*" >&2
    local install=("${as_root[@]}" env DEBIAN_FRONTEND=noninteractive
                   apt-get install -y -q --no-install-recommends "$@")
    "${install[@]}" >&2 || { "${as_root[@]}" apt-get update -q >&2 && "${install[@]}" >&2; }
}

if ! fuzzer_links; then
    # clang brings the runtime on most releases; Debian 12 and later ship it separately.
    apt_install clang pkg-config libconfig-dev libgsl-dev || true
    if ! fuzzer_links && apt-cache show libclang-rt-dev >/dev/null 2>&1; then
        apt_install libclang-rt-dev || true
    fi
    if ! fuzzer_links; then
        echo "fuzz.sh: clang cannot build a libFuzzer target (-fsanitize=fuzzer)" >&2
        exit 2
    fi
fi

# ---- build ----------------------------------------------------------------------------------
# The parser's sources, as tests/fuzz/sources lists them (make check links the same list).
mapfile -t src < <(grep -v -e '^#' -e '^[[:space:]]*$' tests/fuzz/sources)
cflags=(-std=c11 -D_POSIX_C_SOURCE=200809L -g -O1 -fno-omit-frame-pointer
        -fsanitize=address,undefined -fno-sanitize-recover=all -ffp-contract=off
        -Wall -Wextra -Iinclude -Isrc)
read -r -a pkg_cflags <<< "$(pkg-config --cflags libconfig gsl)"
read -r -a pkg_libs <<< "$(pkg-config --libs libconfig gsl)"
objs=()
for s in "${src[@]}"; do
    o=$obj/$(basename "$s" .c).o
    clang "${cflags[@]}" "${pkg_cflags[@]}" -fsanitize=fuzzer-no-link -c "$s" -o "$o" || exit 2
    objs+=("$o")
done
clang "${cflags[@]}" "${pkg_cflags[@]}" -fsanitize=fuzzer tests/fuzz/fuzz_scene.c "${objs[@]}" \
    -o "$out/fuzz_scene" "${pkg_libs[@]}" -lm || exit 2

# ---- seeds ----------------------------------------------------------------------------------
rm -rf "$out/seed" && mkdir -p "$out/seed"
n_seed=0
for d in inputs/*.deck tests/data/*.deck; do
    [ -f "$d" ] || continue
    cp "$d" "$out/seed/$(basename "$d")"
    n_seed=$((n_seed + 1))
done
# A few seeds that carry overrides (the harness passes the lines after "#@set" as --set).
for d in inputs/*.deck; do
    [ -f "$d" ] || continue
    { cat "$d"; printf '%s\n' '#@set' 'run.steps=5' 'spheres.[0].radius=0.25' \
        'physics.gravity=[0,0,-1]'; } >"$out/seed/set-$(basename "$d")"
    n_seed=$((n_seed + 1))
done

# ---- fuzz -----------------------------------------------------------------------------------
rm -f "$out/artifacts"/*
# Allocations above 1 GB fail (return NULL) instead of aborting, so decks asking for huge
# counts exercise the out-of-memory paths; the RSS limit stops runaway growth.
export ASAN_OPTIONS=allocator_may_return_null=1:max_allocation_size_mb=1024:detect_leaks=1
export LSAN_OPTIONS=suppressions=$PWD/tests/fuzz/lsan.supp:print_suppressions=0
export UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1
export NBEP_FUZZ_TMP=$PWD/$out/tmp
echo "fuzz.sh: fuzzing nbep_scene_load for $seconds s with $jobs job(s), $n_seed seeds" >&2
log=$out/fuzz.log
# -fork keeps going after a finding (each is saved) until the time is up.
set +e
"$out/fuzz_scene" -fork="$jobs" -ignore_crashes=1 -ignore_timeouts=1 -ignore_ooms=1 \
    -max_total_time="$seconds" -timeout=10 -rss_limit_mb=2560 -max_len=8192 \
    -dict=tests/fuzz/deck.dict -artifact_prefix="$out/artifacts/" -print_final_stats=1 \
    "$out/corpus" "$out/seed" >"$log" 2>&1
status=$?
set -e
grep -E '^#[0-9]+: cov: .*' "$log" | tail -n 1 >&2 || true
grep -E '^INFO: fuzzed for|^stat::' "$log" | head -n 8 >&2 || true

# ---- report ---------------------------------------------------------------------------------
shopt -s nullglob
findings=("$out"/artifacts/crash-* "$out"/artifacts/leak-* "$out"/artifacts/timeout-* \
          "$out"/artifacts/oom-* "$out"/artifacts/slow-unit-*)
if [ "${#findings[@]}" -eq 0 ]; then
    if [ "$status" -ne 0 ] && ! grep -q 'INFO: exiting: 0' "$log"; then
        echo "fuzz.sh: the fuzzer stopped with status $status and no finding; see $log" >&2
        tail -n 20 "$log" >&2
        exit 1
    fi
    echo "fuzz.sh: no findings ($(ls "$out/corpus" | wc -l) inputs in the corpus)" >&2
    exit 0
fi
echo "fuzz.sh: ${#findings[@]} finding(s):" >&2
for f in "${findings[@]}"; do
    # Replay once for the report's first lines (a timeout is replayed with a short limit).
    "$out/fuzz_scene" -timeout=10 -rss_limit_mb=2560 "$f" >"$f.txt" 2>&1 || true
    echo "== $f ($(wc -c <"$f") bytes)" >&2
    grep -E 'ERROR|SUMMARY|runtime error|Direct leak|#[0-9] 0x[0-9a-f]+ in (nbep|scene|config)' \
        "$f.txt" | head -n 8 >&2 || true
done
exit 1
