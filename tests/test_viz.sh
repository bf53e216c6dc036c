#!/usr/bin/env bash
# Looking at results: scripts/render.py draws chosen frames of a real run to PNG (3-D and a
# projection, frames counted from the end too, a frame out of range refused with one line),
# and, when the build writes XDMF sidecars, RUN.xmf beside RUN.h5 resolves in a reader
# (scripts/check_xdmf.py; with ParaView's pvpython installed, ParaView itself reads it).
# Skipped when /usr/bin/python3 lacks h5py or matplotlib.
. "$(dirname "$0")/lib.sh"
need_py h5py matplotlib
test_tmp viz
is_png() { [ -s "$1" ] && [ "$(head -c 8 "$1" | od -An -tx1 | tr -d ' \n')" = 89504e470d0a1a0a ]; }

cat >"$tmp/viz.deck" <<'EOF'
# 40 spheres falling in a unit box, 6 frames with velocities
run: { steps = 50; dt = 2.0e-3; threads = 1; seed = 9; };
physics: { gravity = [0.0, 0.0, -9.81]; restitution = 0.9; };
box: { min = [0.0, 0.0, 0.0]; max = [1.0, 1.0, 1.0]; };
spheres = ( { count = 40; radius = 0.04; mass = 1.0; place = "random"; speed = 1.0; } );
output: { file = "build/tests/tmp/viz/viz.h5"; every = 10; fields = ["position", "velocity"]; };
EOF
bin/nbep run "$tmp/viz.deck" --quiet
check "the run writes its file" "[ -s '$tmp/viz.h5' ]"

"$PY" scripts/render.py "$tmp/viz.h5" --frames 0,2,-1 --out "$tmp/png" >"$tmp/render.out" 2>&1
check "render.py draws frames 0, 2 and the last (steps 0, 20, 50)" \
    "is_png '$tmp/png/viz-step-000000.png' && is_png '$tmp/png/viz-step-000020.png' &&
     is_png '$tmp/png/viz-step-000050.png'"
check "render.py prints each image's path" "[ \$(wc -l <'$tmp/render.out') = 3 ]"
"$PY" scripts/render.py "$tmp/viz.h5" --frames -1 --view xz --color height --out "$tmp/png" \
    >/dev/null 2>&1
check "render.py draws a projection to scale, named for its colouring" "is_png '$tmp/png/viz-step-000050-xz-height.png' && [ ! -e '$tmp/png/viz-step-000050-xz.png' ]"
"$PY" scripts/render.py "$tmp/viz.h5" --frames 6 --out "$tmp/png" >"$tmp/bad.out" 2>&1
rc=$?
check "a frame past the last is refused (exit $rc)" \
    "[ $rc != 0 ] && grep -q 'frame 6 is outside the 6 complete frames' '$tmp/bad.out'"

# a periodic box has no walls: the box drawn is the file's (box_min, box_max), not the spheres'
cat >"$tmp/periodic.deck" <<'EOF'
run: { algorithm = "predictive"; neighbors = "cells"; steps = 4; dt = 0.05; threads = 1; };
box: { min = [-1.0, 0.0, 0.0]; max = [5.0, 7.0, 6.5]; periodic = [true, true, true]; };
spheres = ( { count = 27; radius = 0.5; mass = 1.0; place = "lattice"; speed = 1.0; } );
output: { file = "build/tests/tmp/viz/periodic.h5"; every = 2; };
EOF
bin/nbep run "$tmp/periodic.deck" --quiet
check "render.py takes a periodic run's box from the file" \
    "'$PY' - '$tmp/periodic.h5' <<'PYEOF'
import sys, h5py
sys.path.insert(0, 'scripts')
import render
f = h5py.File(sys.argv[1], 'r')
lo, hi, boxed = render.box_of(f, f['frames/position'][0], f['spheres/radius'][:])
assert boxed and list(lo) == [-1.0, 0.0, 0.0] and list(hi) == [5.0, 7.0, 6.5], (lo, hi, boxed)
PYEOF"

# an axis far shorter than the longest (the hopper's groove, 0.16 across and 7 long) gets no
# ticks, whose labels fell on one another, and its extent under the title; the others keep a
# few
check "render.py's 3-d view: no ticks on an axis a tenth of the longest or less" \
    "MPLBACKEND=Agg '$PY' - <<'PYEOF'
import sys, types
import numpy as np
import matplotlib.pyplot as plt
sys.path.insert(0, 'scripts')
import render
lo, hi = np.array([-0.08, -7.0, 0.0]), np.array([0.08, 0.0, 0.16])
fig = plt.figure()
args = types.SimpleNamespace(size=6.0)
ax, _ = render.draw_3d(fig, np.array([[0.0, -1.0, 0.1]]), np.array([0.03]), None, lo, hi,
                       False, args)
assert len(ax.get_xticks()) == 0 and len(ax.get_zticks()) == 0, (ax.get_xticks(), ax.get_zticks())
assert len(ax.get_yticks()) > 2
# and at most 5 ticks on the others (the default put 8 on this y, 7 on the hopper's x, their
# labels overlapping)
assert len([t for t in ax.get_yticks() if -7.0 <= t <= 0.0]) <= 5, ax.get_yticks()
assert ax.short == ['x -0.08 .. 0.08', 'z 0 .. 0.16'], ax.short
PYEOF"

# a projection draws each plane it sees edge-on as a line (the hopper's groove in xz), and no
# other: a plane whose normal has a part along the hidden axis is no line in that view
check "render.py's projections: the planes seen edge-on, as lines through their points" \
    "MPLBACKEND=Agg '$PY' - <<'PYEOF'
import sys, types
import numpy as np
import matplotlib.pyplot as plt
sys.path.insert(0, 'scripts')
import render
s = np.sqrt(0.5)
planes = (np.array([[s, 0.0, s], [-s, 0.0, s], [0.0, 1.0, 0.0], [0.0, 0.6, 0.8]]),
          np.array([0.0, 0.1, -2.0, 0.5]))
def lines(view):
    fig = plt.figure()
    args = types.SimpleNamespace(view=view)
    ax, _ = render.draw_2d(fig, np.array([[0.0, 0.0, 1.0]]), np.array([0.1]), None,
                           np.array([-1.0, -1.0, 0.0]), np.array([1.0, 1.0, 2.0]), False,
                           args, planes)
    got = ax.get_lines()
    plt.close(fig)
    return got
xz, yz, xy = lines('xz'), lines('yz'), lines('xy')
assert (len(xz), len(yz), len(xy)) == (2, 2, 1), (len(xz), len(yz), len(xy))
for line, (n, off) in zip(xz, [((s, s), 0.0), ((-s, s), 0.1)]):
    for p in line._xy1, line._xy2:  # both points it was drawn through lie on the plane
        assert abs(n[0] * p[0] + n[1] * p[1] - off) < 1e-12, (n, off, p)
PYEOF"

check "render.py's projections: the nearest sphere drawn last, from the side each view looks from" \
    "MPLBACKEND=Agg '$PY' - <<'PYEOF'
import sys, types
import numpy as np
import matplotlib.pyplot as plt
sys.path.insert(0, 'scripts')
import render
lo, hi = np.array([-2.0, -2.0, -2.0]), np.array([2.0, 2.0, 2.0])
# each view: a sphere in front (across 0) and one behind it (across 0.5): the viewer looks
# from +z for xy, from -y for xz (x across, z up), from +x for yz
for view, front, back in (('xy', [0.0, 0.0, 1.0], [0.5, 0.0, -1.0]),
                          ('xz', [0.0, -1.0, 0.0], [0.5, 1.0, 0.0]),
                          ('yz', [1.0, 0.0, 0.0], [-1.0, 0.5, 0.0])):
    fig = plt.figure()
    for pos in (np.array([front, back]), np.array([back, front])):
        _, ec = render.draw_2d(fig, pos, np.array([0.1, 0.1]), np.array([1.0, 2.0]), lo, hi,
                               False, types.SimpleNamespace(view=view))
        across = ec.get_offsets()[:, 0]
        assert list(across) == [0.5, 0.0], (view, pos.tolist(), across)
    plt.close(fig)
# a pile at rest: its speed bar from 0
fig = plt.figure()
_, ec = render.draw_2d(fig, np.zeros((2, 3)), np.array([0.1, 0.1]), np.zeros(2), lo, hi, False,
                       types.SimpleNamespace(view='xy'))
render.colour_range(ec, np.zeros(2), 'speed')
assert ec.get_clim() == (0.0, 1.0), ec.get_clim()
PYEOF"

# every run writes RUN.xmf beside RUN.h5 (ParaView and VisIt open it as animated spheres)
check "a run writes its XDMF sidecar" "[ -s '$tmp/viz.xmf' ]"
check "the sidecar resolves in a reader" "'$PY' scripts/check_xdmf.py '$tmp/viz.xmf' >/dev/null"
if [ -x /usr/bin/pvpython ]; then
    check "ParaView reads the sidecar" \
        "/usr/bin/pvpython scripts/check_xdmf.py --paraview '$tmp/viz.xmf' >/dev/null 2>&1"
fi

# a run file named in Latin-1 bytes (r\xe9sultat.h5): XML cannot name it, so no sidecar (until
# 2026-12-02 one that XML parsers refuse), one warning saying so, --quiet too, and the check's
# report gives the sidecar as null; a sidecar an older run left at that path goes
lat="$tmp/r"$'\xe9'"sultat"
cp "$tmp/viz.xmf" "$lat.xmf" # an earlier run's sidecar (a file of the user's there is refused: test_cli.sh)
bin/nbep run inputs/two-spheres.deck --quiet -o "$lat.h5" 2>"$tmp/lat.err"
rc=$?
check "a run into a Latin-1 name ends (exit 0, got $rc) with its file and no sidecar" \
    "[ $rc = 0 ] && [ -s '$lat.h5' ] && [ ! -e '$lat.xmf' ]"
check "... and one warning line naming the file and why" \
    "[ \$(wc -l <'$tmp/lat.err') = 1 ] && grep -aq 'sultat.h5: its name is not UTF-8 text' '$tmp/lat.err' &&
     grep -q 'no sidecar is written' '$tmp/lat.err'"
bin/nbep check inputs/two-spheres.deck -o "$lat.h5" --quiet --summary - >"$tmp/lat.json" 2>/dev/null
check "nbep check's report gives its sidecar as null" "grep -q '\"sidecar\": null' '$tmp/lat.json'"
bin/nbep run inputs/two-spheres.deck --quiet -o "$tmp/plain.h5" 2>"$tmp/plain.err"
check "a UTF-8 name gets its sidecar and no warning" "[ -s '$tmp/plain.xmf' ] && [ ! -s '$tmp/plain.err' ]"
# a resumed run decides it as a new one does: a Latin-1 file continued to more steps writes no
# sidecar, removes one left there (until 2026-12-02 a resume kept it) and says why; frames without positions would have none anyway, so a run of those is
# not warned of
cp "$tmp/viz.xmf" "$lat.xmf" # an earlier run's sidecar (a file of the user's there is refused: test_cli.sh)
bin/nbep run inputs/two-spheres.deck --quiet --resume "$lat.h5" --set run.steps=2500 \
    2>"$tmp/lat-resume.err"
rc=$?
check "a Latin-1 run resumed (exit 0, got $rc) writes no sidecar and warns once" \
    "[ $rc = 0 ] && [ ! -e '$lat.xmf' ] && [ \$(wc -l <'$tmp/lat-resume.err') = 1 ] &&
     grep -q 'no sidecar is written' '$tmp/lat-resume.err'"
bin/nbep run inputs/two-spheres.deck --quiet -o "$lat-v.h5" --set 'output.fields=["velocity"]' \
    2>"$tmp/lat-v.err"
rc=$?
check "a Latin-1 run without positions (exit 0, got $rc) is not warned of a sidecar" \
    "[ $rc = 0 ] && [ -s '$lat-v.h5' ] && [ ! -e '$lat-v.xmf' ] && [ ! -s '$tmp/lat-v.err' ]"
test_end viz
