#!/usr/bin/env bash
# make pgo: bin/nbep built with GCC's profile-guided optimisation (-fprofile-use) and link-time
# optimisation (-flto), for production runs (README, Building for production runs).
#
#   1. build/pgo: every object built instrumented (-fprofile-generate), linked as build/pgo/nbep;
#   2. that program runs short training scenes (below), which write a profile beside each object
#      (build/pgo/*.gcda);
#   3. the objects are built again from that profile, and linked with link-time optimisation;
#   4. the result runs three check scenes beside the plain build's program (build/nbep, made by
#      `make pgo` first) and must write the same frames and stats, bit for bit (h5diff, exact:
#      GCC keeps IEEE arithmetic under both optimisations, no -ffast-math and contraction off,
#      so only the speed may change); then, and only then, it replaces bin/nbep.
#
# The training scenes are the hot paths users run: the dense periodic fluid at phi = 0.30 and
# 0.50 in cells mode (one thread, and the team loop on two), the paper's box in all-pairs and
# grid modes, and a granular pour (gravity, e = 0.5) and the hopper (planes). Code they do not
# reach keeps its normal optimisation (-fprofile-partial-training). About 2 minutes on 2 cores.
#
# Environment: CFLAGS is added to both builds.
set -euo pipefail
cd "$(dirname "$0")/.."

dir=build/pgo
plain=build/nbep
if [ ! -x "$plain" ]; then
    echo "pgo.sh: $plain is missing; run 'make pgo', which builds it first" >&2
    exit 2
fi
for tool in gcc-ar h5diff; do
    if ! command -v "$tool" >/dev/null 2>&1; then
        echo "pgo.sh: $tool not found (scripts/install-deps.sh installs it)" >&2
        exit 2
    fi
done

build() { # CFLAGS for this phase; the program is $dir/nbep
    make -s BUILD="$dir" AR=gcc-ar CFLAGS="${CFLAGS:-} $1" "$dir/nbep"
}

echo "pgo.sh: 1/4 instrumented build in $dir"
rm -rf "$dir"
mkdir -p "$dir/train" "$dir/check"
# counters updated atomically where the training runs two threads (the team loop)
build "-fprofile-generate -fprofile-update=prefer-atomic"

echo "pgo.sh: 2/4 training scenes"
t=$dir/train
fluid=(inputs/hard-sphere-fluid.deck --quiet --set 'output.fields=[]' --set output.stats=false)
dense=(--set 'box.max=[32.2398390803, 32.2398390803, 32.2398390803]' --dt 0.05)
run() { # OUT ARGS...: one training or check run, its output under OUT
    local out=$1
    shift
    "$@" -o "$out.h5" --summary "$out.json" >"$out.log" 2>&1 ||
        { echo "pgo.sh: '$*' failed; its output: $out.log" >&2; exit 1; }
}
run "$t/fluid30" "$dir/nbep" run "${fluid[@]}" -n 8 -t 1
run "$t/fluid50" "$dir/nbep" run "${fluid[@]}" "${dense[@]}" -n 12 -t 1
NBEP_TEAM=always run "$t/fluid30-team" "$dir/nbep" run "${fluid[@]}" -n 4 -t 2
run "$t/paper-all" "$dir/nbep" run inputs/paper-box.deck --quiet -n 20 -t 1
run "$t/paper-grid" "$dir/nbep" run inputs/paper-box.deck --quiet -n 100 -t 1 \
    --set 'run.neighbors="grid"'
run "$t/pile" "$dir/nbep" run inputs/pile.deck --quiet -n 300 -t 1
run "$t/hopper" "$dir/nbep" run inputs/hopper.deck --quiet -n 600 -t 1

echo "pgo.sh: 3/4 build from the profile, with link-time optimisation"
# the objects and programs go, the profiles (*.gcda) stay beside where the objects will be
rm -f "$dir"/*.o "$dir"/*.d "$dir/libnbep.a" "$dir/nbep"
build "-fprofile-use -fprofile-partial-training -Wno-missing-profile -flto=$(nproc 2>/dev/null || echo 1)"

echo "pgo.sh: 4/4 the same frames as $plain"
c=$dir/check
check() { # NAME ARGS...: the scene run by both programs, frames and stats compared exactly
    local name=$1
    shift
    run "$c/$name-plain" "$plain" run "$@" --quiet
    run "$c/$name-pgo" "$dir/nbep" run "$@" --quiet
    for group in /frames /stats; do
        if ! h5diff -q "$c/$name-plain.h5" "$c/$name-pgo.h5" "$group" "$group" >/dev/null 2>&1; then
            echo "pgo.sh: $name: $group differs from $plain's; bin/nbep left as it was" >&2
            exit 1
        fi
    done
    echo "pgo.sh:   $name: frames and stats identical"
}
check fluid50 inputs/hard-sphere-fluid.deck "${dense[@]}" -n 4 -t 2 --set output.every=2
check paper-grid inputs/paper-box.deck -n 30 -t 2 --set 'run.neighbors="grid"'
check pile inputs/pile.deck -n 250 -t 2 --set output.every=50

mkdir -p bin
cp "$dir/nbep" bin/nbep.tmp
mv bin/nbep.tmp bin/nbep
echo "pgo.sh: bin/nbep is the profile-guided build ($(bin/nbep --version | head -1))"
