#!/usr/bin/env bash
# Prepares build/dev for a borrowed 16-core node (run here, on this project's machine): the kit
# (bin/nbep with its libraries and loader, scripts/pack-kit.sh), EDMD Single built for each
# fluid's two stop times, its start files (init.sph, the positions of nbep's melt at T1 = 1,
# which the node melts again bit for bit) and scripts/handover.c. Then run.sh on the node.
#   EDMD=/path/to/EDMD docs/figures/node16-1130/prep.sh
set -eu
cd "$(dirname "$0")/../../.."
E=${EDMD:-/work/scratch/edmd}
D=build/dev
rm -rf "$D" && mkdir -p "$D/w"
scripts/pack-kit.sh "$D/kit"
cc -O2 -pthread scripts/handover.c -o "$D/handover"
side() { awk -v n="$1" -v p="$2" 'BEGIN { printf "%.12g", (n * atan2(0, -1) / (6 * p)) ^ (1 / 3) }'; }
for sc in "256000 0.30 0.5" "32000 0.30 3" "32000 0.50 0.75"; do
    set -- $sc
    L=$(side "$1" "$2")
    cat >"$D/w/melt.deck" <<E2
run: { algorithm = "predictive"; steps = 20; dt = 0.05; threads = 2; seed = 1; neighbors = "cells"; };
box: { min = [0.0, 0.0, 0.0]; max = [$L, $L, $L]; periodic = [true, true, true]; };
spheres = ( { count = $1; radius = 0.5; mass = 1.0; place = "lattice"; speed = 1.7320508075688772; } );
output: { file = "$D/w/melt.h5"; every = 20; fields = ["position", "velocity"]; stats = false; };
E2
    bin/nbep run "$D/w/melt.deck" --quiet
    /usr/bin/python3 - "$D/w/melt.h5" "$L" "$D/w/init-$1-$2.sph" <<'PYEOF'
import sys, h5py
f = h5py.File(sys.argv[1], "r"); L = float(sys.argv[2])
p = f["/frames/position"][-1]
with open(sys.argv[3], "w") as o:
    o.write("%d\n%.12f %.12f %.12f\n" % (len(p), L, L, L))
    for x in p:
        o.write("a %.15f %.15f %.15f 0.5\n" % (x[0] % L, x[1] % L, x[2] % L))
PYEOF
    for T in 0.1 $(awk -v s="$3" 'BEGIN { print 0.1 + s }'); do
        dir="$D/edmd-$1-$2-$T"
        cp -r "$E/Single" "$dir"
        sed -i -e "s/^double maxtime = [0-9.e+-]*;/double maxtime = $T;/" \
            -e "s/^double writeinterval = [0-9.e+-]*;/double writeinterval = $T;/" \
            -e "s/^double snapshotinterval = [0-9.e+-]*;/double snapshotinterval = $T;/" \
            -e "s/^int initialconfig = [0-9]*;/int initialconfig = 0;/" \
            -e "s/^const int usethermostat = 1;/const int usethermostat = 0;/" "$dir/mdSingle.c"
        (cd "$dir" && make -s >build.log 2>&1 && rm -f ./*.o) || { echo "EDMD build failed: $dir" >&2; exit 1; }
    done
done
tar cJf "$D/inits.tar.xz" -C "$D/w" $(cd "$D/w" && ls init-*.sph)
rm -rf "$D/w"
du -sh "$D"
