#!/usr/bin/env bash
# Frames bitwise identical for any thread count, past this project's 2 cores: on a 16-core node,
# each scene run on 1, 2, 4, 8 and 16 threads (the kit of docs/figures/node16-e053a30/prep.sh,
# build/dev carried), and every array of the file that a run's physics writes (/frames, /stats)
# compared bit for bit with the one-thread run's (h5py, the node's own Python). Scenes: the
# hard-sphere fluid (cells mode, the team loop: the run's own choice and NBEP_TEAM=always), the
# same cooling at e = 0.9 (resumed, the team too), a 300-sphere pour under gravity (cells, grid
# with NBEP_TEAM=cycle, all pairs), the paper's box (all pairs, grid, cells). Prints one line a
# comparison and "identity: N of N equal"; exit 1 if any differs.
#   OUT=/tmp/out bash docs/figures/node16-1204b/identity.sh
# Prepared at the seventh loan and not run on a node (none was lent again that session); run
# on this project's 2-core machine with THREADS="1 3 4" and PYTHON=/usr/bin/python3 instead.
set -u
cd "$(dirname "$0")/../../.." || exit 1
D=$PWD/build/dev
K=$D/kit/lib
LD=$(echo "$K"/ld-linux*)
W=/tmp/ident
R=${OUT:-/tmp/out}
THREADS=${THREADS:-"1 2 4 8 16"}
PYTHON=${PYTHON:-python3}
rm -rf "$W" && mkdir -p "$W" "$R"
nb() { "$LD" --library-path "$K" "$D/kit/nbep.bin" "$@"; }
export OMP_PLACES=cores OMP_PROC_BIND=close
# the pour to 0.45 s, where it crowds (all pairs to 0.3 s: at 0.6 s it took 188 s of one core)
pour=(inputs/pile.deck -n 450 --set spheres.[0].count=300 --set 'box.max=[0.3873, 0.3873, 1.2]'
      --set output.every=50)
paper=(inputs/paper-box.deck -n 100 --set spheres.[0].count=4096 --set output.every=25)
fluid=(inputs/hard-sphere-fluid.deck -n 20 --set output.every=5)
run() { # name team args... : one file a thread count
    local name=$1 team=$2 t
    shift 2
    for t in $THREADS; do
        NBEP_TEAM=$team nb run "$@" -t "$t" -q -o "$W/$name-t$t.h5" ||
            echo "run failed: $name $t" >>"$R/errors.txt"
    done
}
t0=$(date +%s)
run fluid-own "" "${fluid[@]}"
run fluid-always always "${fluid[@]}"
nb run "${fluid[@]}" -t 16 -q -o "$W/melt.h5"
for t in $THREADS; do
    cp "$W/melt.h5" "$W/cool-t$t.h5"
    nb run "${fluid[@]}" -n 40 --set physics.restitution=0.9 --resume "$W/cool-t$t.h5" -t "$t" -q ||
        echo "run failed: cool $t" >>"$R/errors.txt"
done
run pour-cells "" "${pour[@]}"
run pour-grid cycle "${pour[@]}" --set 'run.neighbors="grid"'
run pour-all "" "${pour[@]}" -n 300 --set 'run.neighbors="all"'
run paper-all "" "${paper[@]}"
run paper-grid "" "${paper[@]}" --set 'run.neighbors="grid"'
run paper-cells "" "${paper[@]}" --set 'run.neighbors="cells"'
echo "runs: $(( $(date +%s) - t0 )) s" >"$R/identity-log.txt"
"$PYTHON" - "$W" "$THREADS" >"$R/identity.txt" 2>&1 <<'PYEOF'
import sys, glob, os, h5py, numpy as np
w, threads = sys.argv[1], sys.argv[2].split()
names = sorted({os.path.basename(p).rsplit('-t', 1)[0] for p in glob.glob(w + '/*-t*.h5')})
bad = total = 0
def arrays(f):
    out = {}
    def visit(name, obj):
        if isinstance(obj, h5py.Dataset) and (name.startswith('frames') or name.startswith('stats')):
            out[name] = obj[()]
    f.visititems(visit)
    return out
for n in names:
    with h5py.File(f'{w}/{n}-t{threads[0]}.h5', 'r') as f:
        ref = arrays(f)
    for t in threads[1:]:
        with h5py.File(f'{w}/{n}-t{t}.h5', 'r') as f:
            got = arrays(f)
        diff = [k for k in ref if k not in got or ref[k].shape != got[k].shape or
                ref[k].tobytes() != got[k].tobytes()]
        total += 1
        bad += bool(diff)
        frames = ref['frames/step'].shape[0] if 'frames/step' in ref else 0
        print(f'{n}: {t} threads against {threads[0]}: {"EQUAL" if not diff else "DIFFER " + ",".join(diff)}'
              f' ({len(ref)} arrays, {frames} frames)')
print(f'identity: {total - bad} of {total} equal')
sys.exit(1 if bad else 0)
PYEOF
rc=$?
echo "done: $(( $(date +%s) - t0 )) s, rc $rc" >>"$R/identity-log.txt"
cat "$R/identity.txt" "$R/identity-log.txt" "$R/errors.txt" 2>/dev/null
exit $rc
