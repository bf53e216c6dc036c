#!/usr/bin/env bash
# `nbep run DECK --resume RUN.h5` continues a run from its last complete frame; its frames
# equal an uninterrupted run's bit for bit, for every algorithm, whether the first part
# stopped at its planned end or was killed by SIGTERM at an arbitrary step.
. "$(dirname "$0")/lib.sh"
test_tmp resume
deck=inputs/paper-box.deck
# a dense small box: plenty of collisions in 80 steps
args=(--quiet --set spheres.[0].count=400 --set box.max=[2,2,2] --set output.every=5)

# same_frames A B: every frame of A appears in B at the same step with identical bits, and B
# holds a frame beyond the resume point
same_frames() {
    "$PY" - "$1" "$2" <<'PYEOF'
import sys, h5py, numpy as np
a, b = h5py.File(sys.argv[1], "r"), h5py.File(sys.argv[2], "r")
sa, sb = list(a["frames/step"][:]), list(b["frames/step"][:])
assert a["stats/collisions"][:].sum() > 0, "no collisions: the comparison would prove little"
for k, step in enumerate(sa):
    j = sb.index(step)
    for f in ("position", "velocity"):
        x, y = a["frames/" + f][k], b["frames/" + f][j]
        assert x.tobytes() == y.tobytes(), f"{f} differs at step {step}"
assert sb[-1] == sa[-1]
PYEOF
}

# same_summary A.json B.json: the two JSON summaries agree on every key but the part's own
# seconds, speed, memory and threads: a resumed run's summary is the whole run's (its counts,
# energies, overlaps and pressure from step 0, /frames/totals), as the uninterrupted run's
same_summary() {
    "$PY" - "$1" "$2" <<'PYEOF'
import json, sys
a, b = (json.load(open(p)) for p in sys.argv[1:3])
own = {"setup_seconds", "wall_seconds", "steps_per_second", "peak_rss_bytes", "threads"}
assert a["collisions"] > 0, "no collisions: the comparison would prove little"
diff = {k: (a[k], b.get(k)) for k in a if k not in own and a[k] != b.get(k)}
assert not diff, diff
PYEOF
}

for algo in predictive naive seminaive; do
    bin/nbep run $deck "${args[@]}" -a $algo -n 80 -o $tmp/$algo-whole.h5 \
        --summary $tmp/$algo-whole.json
    # planned stop at step 40, then resume to 80
    bin/nbep run $deck "${args[@]}" -a $algo -n 40 -o $tmp/$algo-part.h5
    bin/nbep run $deck "${args[@]}" -a $algo -n 80 --resume $tmp/$algo-part.h5 \
        --summary $tmp/$algo-resumed.json
    check "$algo: resumed after a planned stop, frames equal the whole run's" \
        "same_frames $tmp/$algo-whole.h5 $tmp/$algo-part.h5"
    check "$algo: and its summary is the whole run's (collisions, energies, overlaps from step 0)" \
        "same_summary $tmp/$algo-whole.json $tmp/$algo-resumed.json"
done
# a file made before 2026-11-30 has no /frames/totals: its resumed run's summary counts its own
# part (the stats rows after the frame), and its energy_initial is the frame's
bin/nbep run $deck "${args[@]}" -n 40 -o $tmp/no-totals-a.h5
cp $tmp/no-totals-a.h5 $tmp/no-totals.h5
"$PY" -c "
import h5py, sys
with h5py.File(sys.argv[1], 'a') as f:
    del f['frames/totals']" $tmp/no-totals.h5
bin/nbep run $deck "${args[@]}" -n 80 --resume $tmp/no-totals.h5 --summary $tmp/no-totals.json
check "without /frames/totals (an older file): the summary counts the resumed part's collisions, and the file gets no totals" \
    "$PY -c '
import h5py, json, sys
s, f = json.load(open(sys.argv[1])), h5py.File(sys.argv[2], \"r\")
part = int(f[\"stats/collisions\"][40:].sum())
assert 0 < part < int(f[\"stats/collisions\"][:].sum()), part
assert s[\"collisions\"] == part, (s[\"collisions\"], part)
assert \"totals\" not in f[\"frames\"]
' $tmp/no-totals.json $tmp/no-totals.h5"

# a file-size limit (ulimit -f; a batch system's per-process file limit): the run keeps room
# ahead of its file (output.c, nbep__output_reserve) and stops at the frame that would pass the
# limit, before writing any of it: exit 1, one line saying so, the JSON summary failed, every
# counted frame readable, and a resume without the limit ends as the uninterrupted run (until
# 2026-12-02 SIGXFSZ killed it mid-write, exit 153, no summary, its lock and .partial left).
# 1400 KiB hold 4 of the 17 frames of 400 spheres (80 steps, 5 apart) with their room (932 kB).
rm -f $tmp/fsize.*
(ulimit -f 1400; exec bin/nbep run $deck "${args[@]}" -n 80 -o $tmp/fsize.h5 \
    --summary $tmp/fsize.json 2>$tmp/fsize.err)
rc=$?
check "a run meeting ulimit -f: exit 1, one line (got $rc: $(head -c 300 $tmp/fsize.err))" \
    "[ $rc = 1 ] && [ \$(wc -l <$tmp/fsize.err) = 1 ] &&
     grep -q '^nbep: $tmp/fsize.h5: no room for frame [0-9]* (step [0-9]*) (.* kept free ahead of the file, for a frame to be written whole): File too large (the file-size limit, ulimit -f); the frames before it are kept\$' $tmp/fsize.err"
check "... its summary failed, no lock or .partial left, its counted frames (some, not all) readable" \
    "\"\$PY\" -c 'import json, sys, h5py, numpy as np
s = json.load(open(sys.argv[1]))
assert s[\"status\"] == \"failed\", s[\"status\"]
f = h5py.File(sys.argv[2], \"r\")
n = int(f[\"frames\"].attrs[\"count\"])
assert 2 <= n < 17, n
assert np.isfinite(f[\"frames/position\"][:n]).all()' $tmp/fsize.json $tmp/fsize.h5 &&
     [ ! -e $tmp/fsize.h5.lock ] && [ ! -e $tmp/fsize.json.partial ]"
bin/nbep run $deck "${args[@]}" -n 80 --resume $tmp/fsize.h5
check "... and resumed without the limit, it ends as the uninterrupted run" \
    "same_frames $tmp/predictive-whole.h5 $tmp/fsize.h5 &&
     h5diff -q $tmp/predictive-whole.h5 $tmp/fsize.h5 /stats"
# the room a run kept ahead of its file goes back to the disk when it ends: the file holds no
# more blocks than its size needs (a file system that cannot reserve keeps none)
check "a finished run's file holds its size in blocks, no room kept past its end ($(stat -c '%b blocks of %B for %s bytes' $tmp/predictive-whole.h5))" \
    "[ \$(( \$(stat -c '%b * %B' $tmp/predictive-whole.h5) )) -le \$(( \$(stat -c %s $tmp/predictive-whole.h5) + 65536 )) ]"

# a file missing a dataset every run writes (a hand-edited or damaged file): one line naming it,
# exit 2 as for a file that is not what it should be, the file as it was (until 2026-12-02 an
# assertion, exit 134; until 2026-12-04 an I/O fault of the read that met the gap, exit 1); a
# whole group gone, /spheres, the same
for ds in stats/step checkpoint/event_kind frames/time spheres; do
    cp $tmp/no-totals-a.h5 $tmp/missing.h5
    "$PY" -c "import h5py, sys; del h5py.File(sys.argv[1], 'r+')[sys.argv[2]]" $tmp/missing.h5 $ds
    cp $tmp/missing.h5 $tmp/missing-before.h5
    timeout 60 bin/nbep run $deck "${args[@]}" -n 80 --resume $tmp/missing.h5 2>$tmp/missing.err
    rc=$?
    want=/$ds
    [ $ds = spheres ] && want=/spheres/radius
    check "a file without /$ds: exit 2, one line naming it, the file unchanged (got $rc: $(head -c 200 $tmp/missing.err))" \
        "[ $rc = 2 ] && [ \$(wc -l <$tmp/missing.err) = 1 ] &&
         grep -qx 'nbep: $tmp/missing.h5 has no $want, which every run writes there: the file is damaged, or no run wrote it (run without --resume to start afresh)' $tmp/missing.err &&
         cmp -s $tmp/missing.h5 $tmp/missing-before.h5"
done
# a count attribute past its rows (no writer leaves one: a damaged or edited file) is refused
# as such, exit 2 as the README's exit table has it for a --resume file that is not what it
# should be, by info too (resume gave exit 1 until 2026-12-04, a review)
# damaged NAME PYTHON [ARG]: the 40-step file copied to $tmp/NAME.h5 and edited by PYTHON (its
# path in sys.argv[1], ARG in sys.argv[2]), the copy before the resume kept as NAME-before.h5;
# then a resume to 80 steps and an info of it, their status in rc and rc_info, the resume's
# stderr in NAME.err. refused NAME WANT: the resume exit 2, its one line WANT (a grep -x
# pattern), the file unchanged.
damaged() {
    cp $tmp/no-totals-a.h5 $tmp/$1.h5
    "$PY" -c "$2" $tmp/$1.h5 "${@:3}"
    cp $tmp/$1.h5 $tmp/$1-before.h5
    timeout 60 bin/nbep run $deck "${args[@]}" -n 80 --resume $tmp/$1.h5 2>$tmp/$1.err
    rc=$?
    timeout 60 bin/nbep info $tmp/$1.h5 >/dev/null 2>$tmp/$1-info.err
    rc_info=$?
}
refused() {
    [ $rc = 2 ] && [ "$(wc -l <$tmp/$1.err)" = 1 ] &&
        grep -qx -- "$2" $tmp/$1.err && cmp -s $tmp/$1.h5 $tmp/$1-before.h5
}
for g in frames stats; do
    damaged overcount "import h5py, sys, numpy as np; h5py.File(sys.argv[1], 'r+')[sys.argv[2]].attrs.modify('count', np.uint64(1000000))" $g
    check "a /$g count past its rows: resume and info exit 2 (got $rc and $rc_info), one line naming it, the file unchanged ($(head -c 200 $tmp/overcount.err))" \
        "[ $rc_info = 2 ] && refused overcount 'nbep: $tmp/overcount.h5: /$g counts 1000000 rows but /$g/step has [0-9]*: the file is damaged, or no run wrote it'"
done

# a damaged global heap (where HDF5 keeps the variable-length strings: the deck, the summary,
# the format): HDF5 1.10 trusts an object's size there and copied past its buffer (SIGSEGV,
# exit 139, in info, --resume and a sweep's look at its files, found 2026-12-05 by a review
# with one flipped byte); nbep walks the collection first and refuses it as damaged, exit 2,
# one line, the file unchanged. Three damages: an object's size (its high byte), an object's
# index (the string is then nowhere), the collection's signature.
for how in size index signature; do
    damaged heap "import sys
d = bytearray(open(sys.argv[1], 'rb').read())
at = d.find(b'GCOL')
assert at > 0 and d[at + 4] == 1, at
first = at + 16  # after GCOL, version, 3 reserved, the 8-byte collection size
{'size': lambda: d.__setitem__(first + 14, d[first + 14] ^ 0xff),
 'index': lambda: d.__setitem__(first, d[first] ^ 0x40),
 'signature': lambda: d.__setitem__(at, ord('X'))}[sys.argv[2]]()
open(sys.argv[1], 'wb').write(d)" $how
    check "a global heap object's $how damaged: resume and info exit 2 (got $rc and $rc_info), one line saying so, the file unchanged ($(head -c 200 $tmp/heap.err))" \
        "[ $rc_info = 2 ] && refused heap 'nbep: $tmp/heap.h5: attribute [a-z_]* points into a damaged part of the file (its global heap): the file is damaged, or no run wrote it' &&
         cmp -s $tmp/heap-info.err $tmp/heap.err"
done

# the root's object header damaged (its checksum fails): exit 2 as for any other part of the
# file (until 2026-12-05 exit 1 here, 2 one object further on), one line, the file unchanged
damaged root "import sys
d = bytearray(open(sys.argv[1], 'rb').read())
at = d.find(b'OHDR')
d[at + 30] ^= 0x55
open(sys.argv[1], 'wb').write(d)"
check "the root's object header damaged: resume and info exit 2 (got $rc and $rc_info), one line, the file unchanged ($(head -c 200 $tmp/root.err))" \
    "[ $rc_info = 2 ] && refused root 'nbep: $tmp/root.h5: cannot read the root attributes: incorrect metadata checksum.*'"

# /stats's count below the frame resumed from, its rows on disk (a kill within the flush of the
# counts can leave /frames's written and /stats's not, nbep__output_commit): those rows are
# kept and the run ends as the uninterrupted one (until 2026-12-05 they were skipped, the
# table jumping from step 30 to 41)
cp $tmp/no-totals-a.h5 $tmp/stats-count.h5
"$PY" -c "import h5py, sys, numpy as np; h5py.File(sys.argv[1], 'r+')['stats'].attrs.modify('count', np.uint64(30))" $tmp/stats-count.h5
bin/nbep run $deck "${args[@]}" -n 80 --resume $tmp/stats-count.h5
check "a /stats count below the resumed frame, its rows there: kept, the run ends as the uninterrupted one" \
    "same_frames $tmp/predictive-whole.h5 $tmp/stats-count.h5 &&
     h5diff -q $tmp/predictive-whole.h5 $tmp/stats-count.h5 /stats"
# what no run leaves: /stats short of the resumed frame's steps, a last row of another step, a
# frame whose time is not its step times dt (a NaN), frames whose steps do not rise: exit 2,
# one line, the file unchanged (until 2026-12-05 each was resumed, silently)
for how in "stats-cut:/stats holds 30:f['stats'].attrs.modify('count', np.uint64(30)); [f['stats/' + c].resize((30,) + f['stats/' + c].shape[1:]) for c in f['stats'] if f['stats/' + c].shape[0] == 40]" \
           "stats-step:the last of them of another step:f['stats/step'][39] = 7" \
           "time-nan:its frame 8 is at step 40, time nan, which no run writes (the time of a frame is its step times run.dt):f['frames/time'][8] = np.nan" \
           "step-order:its frame 3 is at step 10, time 0.01, which no run writes (the steps of its frames rise):f['frames/step'][3] = 10; f['frames/time'][3] = 10 * f.attrs['dt']"; do
    name=${how%%:*}; rest=${how#*:}; want=${rest%%:*}; edit=${rest#*:}
    damaged $name "import h5py, sys, numpy as np
f = h5py.File(sys.argv[1], 'r+')
$edit"
    check "$name: resume exit 2 (got $rc), one line naming it, the file unchanged ($(head -c 250 $tmp/$name.err))" \
        "refused $name '.*' && grep -qF '$want' $tmp/$name.err &&
         grep -q 'the file is damaged, or no run wrote it\$' $tmp/$name.err"
done

# the end line of a resumed run counts the steps it ran and names the step reached (the
# summary's `steps`), as the JSON summary's steps_per_second counts the steps run
loud=("${args[@]:1}") # args without --quiet
bin/nbep run $deck "${loud[@]}" -n 30 -o $tmp/end-line.h5 2>/dev/null
bin/nbep run $deck "${loud[@]}" -n 55 --resume $tmp/end-line.h5 2>$tmp/end-line.err
check "a resumed run's end line: 'ran 25 steps (to step 55) of 400 spheres', its collisions since step 0 ($(tail -n 1 $tmp/end-line.err))" \
    "tail -n 1 $tmp/end-line.err | grep -q '^nbep: ran 25 steps (to step 55) of 400 spheres .*; since step 0: [0-9]* collisions*; energy drift'"
# each resume adds a line to the root attribute `resumed`, which nbep info prints: the step it
# continued from, its threads, the build and its overrides (the root's own stay the first
# part's, by which a sweep knows its runs)
bin/nbep run $deck "${args[@]}" -n 60 -t 1 --resume $tmp/end-line.h5
bin/nbep info $tmp/end-line.h5 >$tmp/end-line.info
check "nbep info lists both resumes, in order, with their threads and overrides" \
    "grep -A1 '^resumed: *step 30: [0-9]* threads*, nbep [^ ]* (commit [^)]*), .*run.steps=55' \
     $tmp/end-line.info | grep -q '^ *step 55: 1 thread, nbep .*run.steps=60; run.threads=1'"
check "and the first part's overrides as they were" \
    "grep -A8 '^overrides:' $tmp/end-line.info | grep -q 'run.steps=30'"

# the grid mode (beyond the paper) keeps horizon events in its slots: they are saved too;
# the cells mode rebuilds its cells and slots at every frame that is a multiple of
# output.every, and resumes from such frames only
cells=(--set 'run.neighbors="cells"')
for mode in grid cells; do
    nb=(--set "run.neighbors=\"$mode\"")
    bin/nbep run $deck "${args[@]}" "${nb[@]}" -n 80 -o $tmp/$mode-whole.h5
    bin/nbep run $deck "${args[@]}" "${nb[@]}" -n 40 -o $tmp/$mode-part.h5
    bin/nbep run $deck "${args[@]}" "${nb[@]}" -n 80 --resume $tmp/$mode-part.h5
    check "predictive $mode: resumed after a planned stop, frames equal the whole run's" \
        "same_frames $tmp/$mode-whole.h5 $tmp/$mode-part.h5"
done
# a periodic fluid (cells and all-pairs modes): positions wrapped into the box and image
# counts restored (all-pairs: its image-horizon events saved in the slots), so the resumed
# frames and /frames/image equal the whole run's too
for mode in cells all; do
    cat > $tmp/periodic-$mode.deck <<EOF2
run: { algorithm = "predictive"; neighbors = "$mode"; dt = 0.02; threads = 2; seed = 5; };
box: { min = [0.0, 0.0, 0.0]; max = [8.0, 8.0, 8.0]; periodic = [true, true, true]; };
spheres = ( { count = 216; radius = 0.5; mass = 1.0; place = "lattice"; speed = 1.7320508; } );
output: { every = 5; };
EOF2
    bin/nbep run $tmp/periodic-$mode.deck --quiet -n 80 -o $tmp/periodic-$mode-whole.h5
    bin/nbep run $tmp/periodic-$mode.deck --quiet -n 40 -o $tmp/periodic-$mode-part.h5
    bin/nbep run $tmp/periodic-$mode.deck --quiet -n 80 --resume $tmp/periodic-$mode-part.h5
    check "predictive $mode, periodic: resumed after a planned stop, frames equal the whole run's" \
        "same_frames $tmp/periodic-$mode-whole.h5 $tmp/periodic-$mode-part.h5"
    check "and so do the image counts, which do move" \
        "$PY - $tmp/periodic-$mode-whole.h5 $tmp/periodic-$mode-part.h5 <<'PYEOF'
import sys, h5py
a, b = h5py.File(sys.argv[1], 'r'), h5py.File(sys.argv[2], 'r')
assert a['frames/image'][:].tobytes() == b['frames/image'][:].tobytes()
assert abs(a['frames/image'][-1]).sum() > 0
p = a['frames/position'][:]
assert p.min() >= 0.0 and p.max() < 8.0
PYEOF"
    check "nbep info names the periodic axes" \
        "bin/nbep info $tmp/periodic-$mode-part.h5 | grep -q '^periodic: *xyz\$'"
    check "and the box" \
        "bin/nbep info $tmp/periodic-$mode-part.h5 | grep -q '^box: *\[0, 0, 0\] to \[8, 8, 8\]\$'"
    # no wall records a periodic box's side: the file's box attributes do, and a resume in
    # another box is refused (it wrapped the frame's spheres into overlaps: 1.9 radii deep in
    # a fluid at phi = 0.30 with sides 3 % shorter), the file left as it was
    sum=$(md5sum < $tmp/periodic-$mode-part.h5)
    bin/nbep run $tmp/periodic-$mode.deck --quiet -n 90 --set 'box.max=[8.0,8.0,8.25]' \
        --resume $tmp/periodic-$mode-part.h5 2>$tmp/periodic-box.err
    rc=$?
    check "predictive $mode, periodic: a resume in another box is refused with exit 2 (got $rc)" \
        "[ $rc = 2 ] && grep -q 'was run in another box than' $tmp/periodic-box.err"
    check "the refused resume leaves the file as it was" \
        "[ \"\$(md5sum < $tmp/periodic-$mode-part.h5)\" = '$sum' ]"
    # another periodic axis: refused as such, not as planes the deck never wrote (it said
    # "holds 8000 spheres and 0 planes but ... makes 8000 and 2", a new user's find)
    bin/nbep run $tmp/periodic-$mode.deck --quiet -n 90 --set 'box.periodic=[true,true,false]' \
        --resume $tmp/periodic-$mode-part.h5 2>$tmp/periodic-axes.err
    rc=$?
    check "predictive $mode, periodic: a resume with another periodic axis is refused with exit 2, naming box.periodic (got $rc: $(cat $tmp/periodic-axes.err))" \
        "[ $rc = 2 ] && grep -q 'was run with box.periodic = \[true, true, true\] but .* makes \[true, true, false\]; resume with the deck' $tmp/periodic-axes.err &&
         [ \"\$(md5sum < $tmp/periodic-$mode-part.h5)\" = '$sum' ]"
done

# ... and where as many walls stand on another axis (z walled, then y): named as box.periodic,
# not as planes of other normals (a review)
bin/nbep run $tmp/periodic-cells.deck --quiet -n 40 --set 'box.periodic=[true,true,false]' \
    -o $tmp/periodic-slit.h5
sum=$(md5sum < $tmp/periodic-slit.h5)
bin/nbep run $tmp/periodic-cells.deck --quiet -n 90 --set 'box.periodic=[true,false,true]' \
    --resume $tmp/periodic-slit.h5 2>$tmp/periodic-slit.err
rc=$?
check "a slit resumed walled on another axis: refused with exit 2, naming box.periodic (got $rc: $(cat $tmp/periodic-slit.err))" \
    "[ $rc = 2 ] && grep -q 'was run with box.periodic = \[true, true, false\] but .* makes \[true, false, true\]; resume' $tmp/periodic-slit.err &&
     [ \"\$(md5sum < $tmp/periodic-slit.h5)\" = '$sum' ]"

# the paper's step (run.order = "step"): its rounds start from the saved slots as time
# order's do, so a resumed run is bitwise the whole run too (periodic all pairs, closed grid)
for mode in all grid; do
    per=$([ $mode = all ] && echo true || echo false)
    cat > $tmp/step-$mode.deck <<EOF2
run: { algorithm = "predictive"; neighbors = "$mode"; order = "step"; dt = 0.05; threads = 2; seed = 5; };
box: { min = [0.0, 0.0, 0.0]; max = [8.0, 8.0, 8.0]; periodic = [$per, $per, $per]; };
spheres = ( { count = 216; radius = 0.5; mass = 1.0; place = "lattice"; speed = 1.7320508; } );
output: { every = 5; };
EOF2
    bin/nbep run $tmp/step-$mode.deck --quiet -n 80 -o $tmp/step-$mode-whole.h5
    bin/nbep run $tmp/step-$mode.deck --quiet -n 40 -o $tmp/step-$mode-part.h5
    bin/nbep run $tmp/step-$mode.deck --quiet -n 80 --resume $tmp/step-$mode-part.h5
    check "predictive $mode, step order: resumed after a planned stop, frames equal the whole run's" \
        "same_frames $tmp/step-$mode-whole.h5 $tmp/step-$mode-part.h5"
done

# cells mode without a box (the hopper: its cells cover the spheres' extent, laid out afresh at
# each rebuild and whenever the spheres leave it, which follows from the state): a resumed run
# is bitwise the whole run too
# (frames every 150 steps: between them, 600 steps in, spheres leave the region 4 times; with
# frames every 25 the rebuilds at frames kept up with them and none was triggered)
hop=(--quiet -t 2 --set 'run.neighbors="cells"' --set output.every=150)
bin/nbep run inputs/hopper.deck "${hop[@]}" -n 600 -o $tmp/hopper-whole.h5
bin/nbep run inputs/hopper.deck "${hop[@]}" -n 150 -o $tmp/hopper-part.h5
bin/nbep run inputs/hopper.deck "${hop[@]}" -n 600 --resume $tmp/hopper-part.h5 2>$tmp/hopper.err
check "predictive cells without a box (hopper): resumed after a planned stop, frames equal the whole run's" \
    "same_frames $tmp/hopper-whole.h5 $tmp/hopper-part.h5"

# a cells-mode file whose last frame is off the grid of output.every (a stop's own frame:
# SIGTERM writes the step it stopped at) continues from its last frame on the grid, dropping
# the frames after it, and ends as the whole run: the same frames, bit for bit, and no other
# (until 2026-11-27 it was refused, and so was every cells run stopped by SIGTERM)
bin/nbep run $deck "${args[@]}" "${cells[@]}" -n 42 -o $tmp/cells-odd.h5
loud_cells=("${args[@]:1}" "${cells[@]}")
bin/nbep run $deck "${loud_cells[@]}" -n 80 --resume $tmp/cells-odd.h5 2>$tmp/cells-odd.err
rc=$?
check "predictive cells: a file that ends at step 42 (every 5) resumes (got $rc)" "[ $rc = 0 ]"
check "from its frame at step 40, saying that the frames after it, to step 42, are dropped" \
    "grep -q 'continues from its frame at step 40, .*to step 42, are dropped' $tmp/cells-odd.err"
check "and its frames are the whole run's, the same steps and bits" \
    "same_frames $tmp/cells-whole.h5 $tmp/cells-odd.h5 && \
     \"\$PY\" -c \"import h5py, sys; a, b = (h5py.File(p, 'r')['frames/step'][:].tolist() \
     for p in sys.argv[1:]); sys.exit(a != b)\" $tmp/cells-whole.h5 $tmp/cells-odd.h5"
# ... but not to a step before that last frame (it cut frames 41 and 42 and exited 0), and the
# frame rule is predictive's alone (naive ignores run.neighbors: it resumes from step 42)
bin/nbep run $deck "${args[@]}" "${cells[@]}" -n 42 -o $tmp/cells-short.h5
sum=$(md5sum < $tmp/cells-short.h5)
bin/nbep run $deck "${args[@]}" "${cells[@]}" -n 41 --resume $tmp/cells-short.h5 2>$tmp/short.err
rc=$?
check "predictive cells: a resume of a file at step 42 to step 41 is refused (got $rc)" \
    "[ $rc = 2 ] && grep -q 'nothing to resume: its last frame is at step 42 and run.steps is 41' $tmp/short.err"
check "the refused resume leaves the file as it was" "[ \"\$(md5sum < $tmp/cells-short.h5)\" = '$sum' ]"
bin/nbep run $deck "${args[@]}" "${cells[@]}" -a naive -n 42 -o $tmp/naive-cells.h5
bin/nbep run $deck "${loud_cells[@]}" -a naive -n 50 --resume $tmp/naive-cells.h5 2>$tmp/naive-cells.err
rc=$?
check "naive with run.neighbors = cells resumes from its last frame, step 42 (got $rc)" \
    "[ $rc = 0 ] && grep -q 'continues from its frame at step 42, which is off' $tmp/naive-cells.err &&
     bin/nbep info $tmp/naive-cells.h5 | grep -q 'step 42: '"
# ... and in every mode and algorithm, the file that results is the uninterrupted run's, frame
# for frame: a stop's own frame off output.every's grid (step 42 of every 5: a shorter run's
# last, or SIGTERM's) is read and dropped (until 2026-11-30 only cells mode dropped it, and
# the others' files held one frame more than the uninterrupted run's: h5diff told them apart)
# ... the stop's frame stays the run's checkpoint until the resumed run writes its first frame
# (a resumed run killed before then, here with no frame due for 10^8 steps, must leave it: the
# run continues from it, not from step 0)
bin/nbep run $deck "${args[@]}" --set output.every=100000000 -n 42 -o $tmp/stop-frame.h5
bin/nbep run $deck "${args[@]}" --set output.every=100000000 -n 100000000 \
    --resume $tmp/stop-frame.h5 2>/dev/null &
pid=$!
sleep 0.5
kill -KILL $pid
wait $pid 2>/dev/null
check "a resumed run killed before its first frame leaves the stop's frame, step 42, in place" \
    "bin/nbep info $tmp/stop-frame.h5 | grep -q '^frames: *2 (last: step 42,'"
for run in "naive all" "seminaive grid" "predictive all" "predictive grid"; do
    set -- $run
    a=$1 m=$2
    nb=(-a $a --set "run.neighbors=\"$m\"")
    bin/nbep run $deck "${args[@]}" "${nb[@]}" -n 80 -o $tmp/off-$a-$m-whole.h5
    bin/nbep run $deck "${args[@]}" "${nb[@]}" -n 42 -o $tmp/off-$a-$m.h5
    bin/nbep run $deck "${args[@]}" "${nb[@]}" -n 61 -t 2 --resume $tmp/off-$a-$m.h5
    bin/nbep run $deck "${args[@]}" "${nb[@]}" -n 80 -t 1 --resume $tmp/off-$a-$m.h5
    check "$a $m: stopped at 42 and 61, resumed to 80 (every 5): h5diff finds the whole run's frames and stats" \
        "h5diff -q $tmp/off-$a-$m-whole.h5 $tmp/off-$a-$m.h5 /frames &&
         h5diff -q $tmp/off-$a-$m-whole.h5 $tmp/off-$a-$m.h5 /stats &&
         { [ $a != predictive ] || h5diff -q $tmp/off-$a-$m-whole.h5 $tmp/off-$a-$m.h5 /checkpoint; }"
    check "and its sidecar lists those frames" \
        "cmp -s $tmp/off-$a-$m-whole.xmf <(sed 's/off-$a-$m\.h5/off-$a-$m-whole.h5/g' $tmp/off-$a-$m.xmf)"
done
# a frame on the grid of the file's own output.every is no stop's frame: a deck that changes
# output.every (naive and all-pairs may) keeps it, frame 40 of every 5 resumed with every 7
bin/nbep run $deck "${args[@]}" -n 40 -o $tmp/every-changed.h5
bin/nbep run $deck "${args[@]}" --set output.every=7 -n 50 --resume $tmp/every-changed.h5
check "a file of every 5 resumed at step 40 with every 7 keeps its frame at step 40" \
    "\"\$PY\" -c \"import h5py, sys; s = h5py.File(sys.argv[1], 'r')['frames/step'][:].tolist(); \
     sys.exit(s != list(range(0, 45, 5)) + [42, 49, 50])\" $tmp/every-changed.h5"
# the same in a periodic box, whose frames' image rows are cut and written as the others are
# (they were written past the stop's frame, at first: its image counts stayed, under the next
# frame's positions)
bin/nbep run $tmp/periodic-all.deck --quiet -n 80 -o $tmp/off-periodic-whole.h5 \
    --summary $tmp/off-periodic-whole.json
bin/nbep run $tmp/periodic-all.deck --quiet -n 42 -o $tmp/off-periodic.h5
bin/nbep run $tmp/periodic-all.deck --quiet -n 61 -t 1 --resume $tmp/off-periodic.h5
bin/nbep run $tmp/periodic-all.deck --quiet -n 80 --resume $tmp/off-periodic.h5 \
    --summary $tmp/off-periodic.json
check "periodic, all pairs: stopped at 42 and 61, resumed to 80: h5diff finds the whole run's frames (images too)" \
    "h5diff -q $tmp/off-periodic-whole.h5 $tmp/off-periodic.h5 /frames &&
     h5diff -q $tmp/off-periodic-whole.h5 $tmp/off-periodic.h5 /checkpoint"
check "and the whole run's summary, its pressure over all 80 steps ($(grep -o '\"pressure\": [^,]*' $tmp/off-periodic.json))" \
    "grep -q '\"pressure\": [0-9]' $tmp/off-periodic.json &&
     same_summary $tmp/off-periodic-whole.json $tmp/off-periodic.json"
# the summary file given as the run's own file: refused before it is opened (it emptied the
# run file, and the failed resume then removed it)
cp $tmp/cells-short.h5 $tmp/victim.h5
bin/nbep run $deck "${args[@]}" "${cells[@]}" -n 90 --resume $tmp/victim.h5 --summary $tmp/victim.h5 \
    2>$tmp/victim.err
rc=$?
check "--resume RUN.h5 --summary RUN.h5 is refused with exit 2 (got $rc), the run file kept" \
    "[ $rc = 2 ] && grep -q 'summary file .* is the run.s file itself' $tmp/victim.err &&
     [ \"\$(md5sum < $tmp/victim.h5)\" = '$sum' ]"
# a refused resume leaves an older summary at --summary as it was (it was opened, so emptied,
# before the deck was checked against the file, then removed)
echo '{"older": true}' >$tmp/older.json
bin/nbep run $deck "${args[@]}" "${cells[@]}" -n 90 --set run.dt=0.002 --resume $tmp/victim.h5 \
    --summary $tmp/older.json 2>$tmp/older.err
rc=$?
check "a resume refused for its dt: exit 2 (got $rc), an older summary kept, no partial one" \
    "[ $rc = 2 ] && grep -q 'run.dt' $tmp/older.err && grep -q older $tmp/older.json &&
     [ ! -e $tmp/older.json.partial ] && [ \"\$(md5sum < $tmp/victim.h5)\" = '$sum' ]"
# cells mode resumes bit for bit only from a multiple of the output.every it was written with
# (its lists are rebuilt there): another output.every is refused, the file as it was (with 7, it
# resumed from the stop's frame at step 42, no rebuild point of the run that wrote it, and
# matched neither deck's uninterrupted run)
bin/nbep run $deck "${args[@]}" "${cells[@]}" --set output.every=7 -n 90 --resume $tmp/victim.h5 \
    2>$tmp/every.err
rc=$?
check "predictive cells: a resume with another output.every is refused with exit 2 (got $rc)" \
    "[ $rc = 2 ] && grep -q 'written with output.every = 5 but .* makes 7' $tmp/every.err &&
     [ \"\$(md5sum < $tmp/victim.h5)\" = '$sum' ]"
# a deck edited in place between the parts (another algorithm and restitution, which a resume
# may change): the resume's line in `resumed` says so, the root still the first part's (the
# file misdescribed how its later frames were made)
cp $deck $tmp/edited.deck
bin/nbep run $tmp/edited.deck "${args[@]}" -n 20 -o $tmp/edited.h5
sed -i -e 's/algorithm = "predictive"/algorithm = "naive"/' \
    -e 's/restitution = [0-9.]*/restitution = 0.5/' $tmp/edited.deck
bin/nbep run $tmp/edited.deck "${args[@]}" -n 30 --resume $tmp/edited.h5
bin/nbep info $tmp/edited.h5 >$tmp/edited.info
check "a resume with a deck edited in place: its line names the algorithm and restitution" \
    "grep -q '^resumed: .*step 20: .*, algorithm naive, restitution 0.5' $tmp/edited.info &&
     grep -q '^algorithm: *predictive' $tmp/edited.info"
# a part with another run.neighbors or run.order (which a resume may change): named in its line
# as the algorithm is (until 2026-11-30 nothing said the later frames were found another way)
bin/nbep run $deck "${args[@]}" -n 20 -o $tmp/ways.h5
bin/nbep run $deck "${args[@]}" -n 30 --set 'run.neighbors="grid"' --set 'run.order="step"' \
    --resume $tmp/ways.h5
bin/nbep info $tmp/ways.h5 >$tmp/ways.info
check "a resume in another neighbors mode and order: its line names them" \
    "grep -q '^resumed: .*step 20: .*, neighbors grid, order step' $tmp/ways.info &&
     ! grep '^resumed:' $tmp/ways.info | grep -q 'algorithm\|restitution'"
# ... and says so at the time, not --quiet (since 2026-12-02 only the file said it), one line
# naming what changed; a part that runs as the first did says nothing of it
no_quiet=("${args[@]:1}")
bin/nbep run $deck "${no_quiet[@]}" -n 40 --set 'run.neighbors="grid"' \
    --set physics.restitution=0.75 --resume $tmp/ways.h5 2>$tmp/ways.err >/dev/null
bin/nbep run $deck "${no_quiet[@]}" -n 50 --resume $tmp/ways.h5 2>$tmp/same.err >/dev/null
# -0 is 0: a file made at e = 0 resumed with -0.0 runs the same physics, and says nothing
bin/nbep run $deck "${no_quiet[@]}" -n 20 --set physics.restitution=0 -o $tmp/zero.h5 \
    2>/dev/null >/dev/null
bin/nbep run $deck "${no_quiet[@]}" -n 30 --set physics.restitution=-0.0 --resume $tmp/zero.h5 \
    2>$tmp/zero.err >/dev/null
check "a resume with restitution -0.0 of a file made at 0 says nothing of a change: $(head -c 200 $tmp/zero.err)" \
    "! grep -q 'first part' $tmp/zero.err && ! bin/nbep info $tmp/zero.h5 | grep -q 'restitution -0'"
check "a hand resume with another restitution and neighbors mode says so on stderr" \
    "[ \"\$(grep -c 'with ' $tmp/ways.err)\" = 1 ] &&
     grep -q '^nbep: .*ways.h5 continues from step 30 with restitution 0.75, neighbors grid, which its first part did not run with' $tmp/ways.err &&
     ! grep -q 'first part' $tmp/same.err"
# the algorithm may change at a resume: a predictive file continued by naive, then by predictive
# again. /checkpoint keeps a row for every frame, naive's frames' rows stale (kind 0: every
# sphere predicted afresh; no resting plane), so the last resume reads the row of its frame
# (naive wrote none, and that resume failed with exit 1, "/checkpoint/event_time has no row 8",
# until 2026-11-30). A file made so before then (its /checkpoint cut short below) resumes from
# positions and velocities, its missing rows written stale.
bin/nbep run $deck "${args[@]}" -n 20 -o $tmp/switch.h5
bin/nbep run $deck "${args[@]}" -a naive -n 40 --resume $tmp/switch.h5
check "naive's frames of a predictive file get /checkpoint rows (9 frames, 9 rows)" \
    "h5ls $tmp/switch.h5/checkpoint/event_kind | grep -q '{9/Inf, 400}'"
cp $tmp/switch.h5 $tmp/switch-old.h5
"$PY" -c "import h5py, sys; f = h5py.File(sys.argv[1], 'r+'); [f['checkpoint/' + c].resize(5, axis=0) for c in f['checkpoint']]" $tmp/switch-old.h5
for f in switch switch-old; do
    timeout 60 bin/nbep run $deck "${args[@]}" -n 60 --resume $tmp/$f.h5 2>$tmp/$f.err
    rc=$?
    check "$f: predictive, naive, predictive again: exit 0 (got $rc: $(head -c 200 $tmp/$f.err))" "[ $rc = 0 ]"
    check "$f: a /checkpoint row for every frame, naive's stale" \
        "$PY - $tmp/$f.h5 <<'PYEOF'
import sys, h5py
f = h5py.File(sys.argv[1], 'r')
steps = list(f['frames/step'][:])
assert steps == list(range(0, 65, 5)), steps
assert all(f['checkpoint/' + c].shape[0] == len(steps) for c in f['checkpoint'])
for k, s in enumerate(steps):
    stale = 25 <= s <= 40
    assert (f['checkpoint/event_kind'][k].max() == 0) == (stale or s == 0), s
    assert not stale or f['checkpoint/rest'][k].min() == f['checkpoint/rest'][k].max() == -1, s
PYEOF"
done

# /checkpoint/rest names each sphere's resting plane, plane 0 too: an elastic run under
# accelerations (no lasting contacts: a resume reads this column alone) with a sphere at rest on
# the first deck plane, one on the second (pressed into it by its own acceleration) and one
# falling free, in each neighbour mode (a mutant drawn at random on 2026-12-05 that skipped
# plane 0 passed every test)
cat >$tmp/rest.deck <<'EOF2'
run: { algorithm = "predictive"; steps = 10; dt = 0.01; threads = 1; };
physics: { gravity = [0.0, 0.0, -9.81]; restitution = 1.0; };
planes = ( { normal = [0.0, 0.0, 1.0]; point = [0.0, 0.0, 0.0]; },
           { normal = [1.0, 0.0, 0.0]; point = [0.0, 0.0, 0.0]; } );
spheres = (
  { position = [2.0, 0.0, 0.5]; velocity = [0.0, 0.0, 0.0]; radius = 0.5; mass = 1.0; },
  { position = [0.5, 0.0, 3.0]; velocity = [0.0, 0.0, 0.0]; radius = 0.5; mass = 1.0;
    acceleration = [-1.0, 0.0, 0.0]; },
  { position = [5.0, 0.0, 3.0]; velocity = [0.0, 0.0, 0.0]; radius = 0.5; mass = 1.0; }
);
output: { every = 5; fields = ["position", "velocity"]; };
EOF2
for nb in all grid cells; do
    bin/nbep run $tmp/rest.deck --quiet --set "run.neighbors=\"$nb\"" -o $tmp/rest-$nb.h5
    check "$nb: /checkpoint/rest names plane 0 and plane 1 where spheres rest on them" \
        "$PY -c \"import h5py, sys; r = h5py.File(sys.argv[1], 'r')['checkpoint/rest'][:].tolist(); assert r == [[-1, -1, -1], [0, 1, -1], [0, 1, -1]], r\" $tmp/rest-$nb.h5"
done

# a deck that asks for stats where the file has none, or the other way: refused, the file as it
# was (a file without /stats resumed with stats aborted after it was changed; the other way
# left /stats short of the frames)
for want in false true; do
    bin/nbep run $deck "${args[@]}" --set output.stats=$want -n 20 -o $tmp/stats-$want.h5
    sum=$(md5sum < $tmp/stats-$want.h5)
    other=$([ $want = true ] && echo false || echo true)
    bin/nbep run $deck "${args[@]}" --set output.stats=$other -n 40 --resume $tmp/stats-$want.h5 \
        2>$tmp/stats.err
    rc=$?
    check "a file made with output.stats = $want resumed with $other: exit 2 (got $rc), file kept" \
        "[ $rc = 2 ] && grep -q 'output.stats' $tmp/stats.err &&
         [ \"\$(md5sum < $tmp/stats-$want.h5)\" = '$sum' ]"
done

# a deck that asks for fewer fields than the file's frames hold (they hold both: a resume
# needs them): refused, the file as it was (until 2026-11-30 accepted, named in `resumed` and
# ignored, the resumed frames holding both after all)
bin/nbep run $deck "${args[@]}" -n 20 -o $tmp/fields.h5
sum=$(md5sum < $tmp/fields.h5)
for fields in '["position"]' '["velocity"]' '[]'; do
    bin/nbep run $deck "${args[@]}" --set "output.fields=$fields" -n 40 --resume $tmp/fields.h5 \
        2>$tmp/fields.err
    rc=$?
    check "a file resumed with output.fields = $fields: exit 2 (got $rc), one line, file kept" \
        "[ $rc = 2 ] && [ \$(wc -l < $tmp/fields.err) = 1 ] && grep -q 'output.fields' $tmp/fields.err &&
         [ \"\$(md5sum < $tmp/fields.h5)\" = '$sum' ]"
done

# cells mode stopped by SIGTERM at whatever step it reached, resumed to a fixed end past it
bin/nbep run $deck "${args[@]}" "${cells[@]}" -n 100000000 -o $tmp/cells-killed.h5 2>/dev/null &
pid=$!
for _ in $(seq 300); do [ -s $tmp/cells-killed.h5 ] && break; sleep 0.1; done
sleep 0.5
kill -TERM $pid
wait $pid 2>/dev/null
rc=$?
last=$(bin/nbep info $tmp/cells-killed.h5 | sed -n 's/^frames: .*last: step \([0-9]*\).*/\1/p')
check "predictive cells: SIGTERM stops the long run with 143 (got $rc) at step $last" \
    "[ $rc = 143 ] && [ -n '$last' ] && [ '$last' -gt 0 ]"
end=$(( ${last:-0} + 30 ))
bin/nbep run $deck "${args[@]}" "${cells[@]}" -n $end -o $tmp/cells-whole2.h5
bin/nbep run $deck "${args[@]}" "${cells[@]}" -n $end --resume $tmp/cells-killed.h5
check "predictive cells: resumed after SIGTERM, every frame equals the uninterrupted run's" \
    "same_frames $tmp/cells-whole2.h5 $tmp/cells-killed.h5"

# a step abandoned by SIGTERM (a fluid with steps of about a second: the loop drops the step's
# events where the signal finds them, and the run ends after the step before, whose stats row
# may lie past the last frame), resumed to a fixed end past it: every frame equals the
# uninterrupted run's, on 2 threads (the team loop). A signal that lands between two steps'
# events (unlikely: those are nearly all of a step) is a plain stop, resumed the same way.
fluid=(inputs/hard-sphere-fluid.deck --quiet -t 2 --set spheres.[0].count=4000
       --set 'box.max=[19.1122779605, 19.1122779605, 19.1122779605]' --set run.dt=30
       --set output.every=2)
bin/nbep run "${fluid[@]}" -n 100000000 -o $tmp/abandoned.h5 2>$tmp/abandoned.err &
pid=$!
for _ in $(seq 300); do [ -s $tmp/abandoned.h5 ] && break; sleep 0.1; done
sleep 2.0
kill -TERM $pid
wait $pid
rc=$?
last=$(bin/nbep info $tmp/abandoned.h5 | sed -n 's/^frames: .*last: step \([0-9]*\).*/\1/p')
grep -q 'which is abandoned' $tmp/abandoned.err || echo "note: the signal came between steps"
check "a fluid's step abandoned by SIGTERM: exit 143 (got $rc), frames up to step $last" \
    "[ $rc = 143 ] && [ -n '$last' ]"
end=$(( ${last:-0} + 3 ))
bin/nbep run "${fluid[@]}" -n $end -o $tmp/abandoned-whole.h5
bin/nbep run "${fluid[@]}" -n $end --resume $tmp/abandoned.h5
check "resumed after the abandoned step, every frame equals the uninterrupted run's" \
    "same_frames $tmp/abandoned-whole.h5 $tmp/abandoned.h5"
check "and so does every stats row" \
    "h5diff -q $tmp/abandoned-whole.h5 $tmp/abandoned.h5 /stats"

# the same with naive, whose pass over the pairs looks at the signal too: all-pairs tests of
# 16384 spheres on 2 threads, a few tenths of a second a step, the signal in the third or so;
# the abandoned step's drift is put back, and nothing of it reaches the file
naive=($deck --quiet -a naive -t 2 --set spheres.[0].count=16384 --set output.every=2
       --set 'output.fields=["position", "velocity"]')
bin/nbep run "${naive[@]}" -n 100000000 -o $tmp/naive-abandoned.h5 2>$tmp/naive-abandoned.err &
pid=$!
for _ in $(seq 300); do [ -s $tmp/naive-abandoned.h5 ] && break; sleep 0.1; done
sleep 1.0
kill -TERM $pid
wait $pid
rc=$?
last=$(bin/nbep info $tmp/naive-abandoned.h5 | sed -n 's/^frames: .*last: step \([0-9]*\).*/\1/p')
grep -q 'which is abandoned' $tmp/naive-abandoned.err || echo "note: the signal came between steps"
check "naive: a step abandoned by SIGTERM: exit 143 (got $rc), frames up to step $last" \
    "[ $rc = 143 ] && [ -n '$last' ]"
end=$(( ${last:-0} + 3 ))
bin/nbep run "${naive[@]}" -n $end -o $tmp/naive-abandoned-whole.h5
bin/nbep run "${naive[@]}" -n $end --resume $tmp/naive-abandoned.h5
check "naive: resumed after the abandoned step, every frame and stats row equals the uninterrupted run's" \
    "same_frames $tmp/naive-abandoned-whole.h5 $tmp/naive-abandoned.h5 &&
     h5diff -q $tmp/naive-abandoned-whole.h5 $tmp/naive-abandoned.h5 /stats"

# a file whose last frame is step 0 (a run of 0 steps, or one whose first step a signal
# abandoned) resumes as the uninterrupted run: frames and every stats row, step 1's counts too
# (all-pairs mode imported frame 0's slots and skipped the first predictions, which the
# uninterrupted run counts in step 1's row: n checks and n - 1 predictions short until
# 2026-11-30), in all-pairs, grid and cells modes
for mode in all grid cells; do
    bin/nbep run $deck "${args[@]}" --set "run.neighbors=\"$mode\"" -n 10 -o $tmp/zero-whole-$mode.h5
    bin/nbep run $deck "${args[@]}" --set "run.neighbors=\"$mode\"" -n 0 -o $tmp/zero-$mode.h5
    bin/nbep run $deck "${args[@]}" --set "run.neighbors=\"$mode\"" -n 10 --resume $tmp/zero-$mode.h5
    check "$mode: resumed from frame 0, every frame and stats row equals the uninterrupted run's" \
        "same_frames $tmp/zero-whole-$mode.h5 $tmp/zero-$mode.h5 &&
         h5diff -q $tmp/zero-whole-$mode.h5 $tmp/zero-$mode.h5 /stats"
done

# a run killed while it wrote a frame: that frame's chunks, extents and chunk indexes reached
# the disk, the superblock's end of allocation did not (HDF5 writes it at a flush). Made here
# as a kill makes it: the rows added and each dataset flushed alone (H5Dflush), then _exit.
# The resume cuts those rows: it failed at its first flush, "addr overflow", exit 1, until
# 2026-11-30 (kill -9 at random moments: 2 of 12 files with a half-written frame)
bin/nbep run $deck "${args[@]}" -n 40 -o $tmp/cut-short.h5
"$PY" - $tmp/cut-short.h5 <<'PYEOF'
import os, sys, h5py
f = h5py.File(sys.argv[1], "r+")
for name in ("frames/position", "frames/velocity"):
    d = f[name]
    n = d.shape[0]
    d.resize(n + 1, axis=0)
    d[n] = d[n - 1]
    d.flush()
os._exit(0)
PYEOF
timeout 60 bin/nbep run $deck "${args[@]}" -n 80 --resume $tmp/cut-short.h5 2>$tmp/cut-short.err
rc=$?
check "a file whose half-written frame lies past its end of allocation resumes (got $rc: $(head -c 200 $tmp/cut-short.err))" \
    "[ $rc = 0 ] && [ ! -s $tmp/cut-short.err ]"
check "and ends as the uninterrupted run's file: frames, stats and slots equal under h5diff" \
    "h5diff -q $tmp/predictive-whole.h5 $tmp/cut-short.h5 /frames &&
     h5diff -q $tmp/predictive-whole.h5 $tmp/cut-short.h5 /stats &&
     h5diff -q $tmp/predictive-whole.h5 $tmp/cut-short.h5 /checkpoint"

# a predictive run at e < 1 keeps state no frame holds (TC clocks; under gravity the held
# spheres, their lasting contacts, caged faces and settling windows): /checkpoint/contacts keeps
# it for the file's last two frames, and the resume continues bit for bit (until 2026-11-30 it
# started them afresh and its frames parted from the uninterrupted run's: a cooling gas from
# its first resumed step, a 300-sphere pile resumed at step 1000 from step 1001; one warning
# line said so). A cooling gas with physics.tc = 0.3, and a small pile in each neighbour mode
# stopped where spheres are held, rest, are slow and were caged (held_at checks there are), on
# output.every's grid and off it (a stop's own frame: cells mode continues from the frame
# before, whose state lies in the other row)
ck_same() { # A B: the uninterrupted run's file and the resumed one end alike
    h5diff -q "$1" "$2" /frames && h5diff -q "$1" "$2" /stats && h5diff -q "$1" "$2" /checkpoint
}
cool=(inputs/hard-sphere-fluid.deck --quiet --set spheres.[0].count=2000
      --set 'box.max=[15.05,15.05,15.05]' --set run.dt=0.5 --set output.every=5
      --set physics.restitution=0.1 --set physics.tc=0.3)
bin/nbep run "${cool[@]}" -n 40 -o $tmp/cool-whole.h5
bin/nbep run "${cool[@]}" -n 20 -o $tmp/cool.h5
timeout 60 bin/nbep run "${cool[@]}" -n 40 --resume $tmp/cool.h5 2>$tmp/cool.err
rc=$?
check "a cooling gas (e = 0.1, tc = 0.3) resumed from step 20: exit 0 (got $rc), nothing said, the uninterrupted run's file" \
    "[ $rc = 0 ] && [ ! -s $tmp/cool.err ] && ck_same $tmp/cool-whole.h5 $tmp/cool.h5"
# held_at FILE STEP [window]: the file's lasting state for the frame at STEP has spheres held
# (on spheres too), resting, caged and with TC clocks, and with `window` free ones partway
# through their settling windows (so that the comparisons above prove something)
held_at() {
    "$PY" - "$@" <<'PYEOF'
import sys, h5py, numpy as np
f = h5py.File(sys.argv[1], "r")
rows = list(f["frames/step"][: int(f["frames"].attrs["count"])])
row = rows.index(int(sys.argv[2]))
tags = list(f["checkpoint/contacts_frame"][:])
assert tags[row % 2] == row, f"no state kept for step {sys.argv[2]}: {tags}"
r = f["checkpoint/contacts"][row % 2]
held = r["rest_still"] > 0
got = dict(held=int(held.sum()), on_spheres=int((held & (r["rest_who"] < 0).any(axis=1)).sum()),
           resting=int((r["rest_n"] > 0).sum()), clocks=int(r["has_last"].sum()),
           caged=int((r["face_who"][:, 0] != -2**31).sum()))
if len(sys.argv) > 3:
    got["window"] = int((~held & (r["slow"] > 0)).sum())
assert min(got.values()) > 0, got
PYEOF
}
pile=(inputs/pile.deck --quiet -t 1 --set 'box.max=[0.3,0.3,0.5]' --set spheres.[0].count=60
      --set output.every=50)
# stop:from:window, the frame resumed from and whether free spheres are partway through their
# settling windows there. Which frames have such spheres moves with the scene's last bits (none
# at step 700 in either mode nor at 750 in grid mode after the minimum bounce of a sphere on
# the floor changed, 2026-12-01; none at 800 in all-pairs mode, then none at 750 in cells mode
# nor 800 in grid mode, after elastic responses took the normal's excess over unit length,
# 2026-12-02), so each mode looks for its first such frame among a few, and fails if it finds
# none (first_window)
first_window() { # MODE: the first of the candidate steps whose frame has spheres mid-window
    local c
    for c in 750 800 700 850 900 650; do
        bin/nbep run "${pile[@]}" "${nb[@]}" -n $c -o $tmp/pile-$1-$c.h5 &&
            held_at $tmp/pile-$1-$c.h5 $c window 2>/dev/null && { echo $c; return; }
    done
    echo none
}
for mode in cells grid all; do
    nb=(--set "run.neighbors=\"$mode\"")
    bin/nbep run "${pile[@]}" "${nb[@]}" -n 950 -o $tmp/pile-$mode-whole.h5 \
        --summary $tmp/pile-$mode-whole.json
    at=$(first_window $mode)
    check "$mode: a frame among steps 650 to 900 with spheres partway through settling (got $at)" \
        "[ $at != none ]"
    [ "$at" = none ] && continue
    case $mode in
        cells) stops="$at:$at:window $((at + 37)):$at:window" ;;
        grid) stops="$at:$at:window 737:737" ;;
        all) stops="$at:$at:window" ;; # all pairs: a slow mode on a pile (8 s for the 950 steps)
    esac
    for spec in $stops; do
        IFS=: read -r stop from window <<<"$spec"
        bin/nbep run "${pile[@]}" "${nb[@]}" -n $stop -o $tmp/pile-$mode-$stop.h5
        held_at $tmp/pile-$mode-$stop.h5 $from $window 2>$tmp/pile-held.err
        check "$mode: the pile stopped at step $stop has held spheres (on spheres too), resting, caged${window:+, settling} ones at step $from ($(tail -n 1 $tmp/pile-held.err))" \
            "[ ! -s $tmp/pile-held.err ]"
        timeout 120 bin/nbep run "${pile[@]}" "${nb[@]}" -n 950 --resume $tmp/pile-$mode-$stop.h5 \
            --summary $tmp/pile-$mode-$stop.json 2>$tmp/pile-$mode.err
        rc=$?
        check "$mode: the pile resumed from step $from: exit 0 (got $rc), nothing said, the uninterrupted run's file" \
            "[ $rc = 0 ] && [ ! -s $tmp/pile-$mode.err ] &&
             ck_same $tmp/pile-$mode-whole.h5 $tmp/pile-$mode-$stop.h5"
        check "$mode: and the uninterrupted run's summary (the energy lost from step 0, plane collisions too)" \
            "same_summary $tmp/pile-$mode-whole.json $tmp/pile-$mode-$stop.json"
    done
done
# writing a frame's state overwrites the row of the frame two before, from which a cells resume
# may still start (it goes back to the last frame at a multiple of output.every: two or more
# back where an earlier part ran with another output.every), so that row is unnamed, on disk,
# before the new records go in. gdb kills a grid part at output.every = 30 (after one at 50)
# as it names the row it wrote for step 810, its records in: until 2026-11-30 that row still
# named the frame at step 750 over step 810's records, and the cells resume from step 750 took
# them silently (the pile then overlapped by 4 % of a radius); now it has no state for that
# frame and says so. Skipped without gdb, or where it cannot stop the run there
if command -v gdb >/dev/null; then
    pour=(inputs/pile.deck --quiet -t 1 --set spheres.[0].count=300)
    bin/nbep run "${pour[@]}" --set 'run.neighbors="grid"' --set output.every=50 -n 700 \
        -o $tmp/torn.h5
    under_gdb timeout -k 5 120 gdb -q -batch -ex 'break tag_slot if row == 18' -ex run -ex kill \
        --args bin/nbep run "${pour[@]}" --set 'run.neighbors="grid"' --set output.every=30 \
        -n 1500 --resume $tmp/torn.h5 >$tmp/gdb-torn 2>&1
    if grep -q 'Breakpoint 1, ' $tmp/gdb-torn; then
        check "killed while it names a frame's row of lasting state: each row named holds its frame's state (no TC clock past the frame's time)" \
            "$PY - $tmp/torn.h5 <<'PYEOF'
import sys, h5py
f = h5py.File(sys.argv[1], 'r')
time = f['frames/time'][: int(f['frames'].attrs['count'])]
tags = f['checkpoint/contacts_frame'][:]
assert len(time) == 18 and tags[1] == 17, (len(time), tags)
for slot, g in enumerate(tags):
    if g >= 0:
        r = f['checkpoint/contacts'][slot]
        late = int(((r['has_last'] > 0) & (r['t_last'] > time[g])).sum())
        assert late == 0, f'row {slot} names frame {g} (t = {time[g]}) but {late} clocks are later'
PYEOF"
        timeout 120 bin/nbep run "${pour[@]}" --set 'run.neighbors="cells"' --set output.every=50 \
            -n 1000 --resume $tmp/torn.h5 2>$tmp/torn.err
        rc=$?
        check "and a cells resume from step 750 starts the state afresh, saying so (exit $rc)" \
            "[ $rc = 0 ] && [ \$(wc -l < $tmp/torn.err) = 1 ] &&
             grep -q '^nbep: warning: .* from step 750, .*TC clocks' $tmp/torn.err"
    else
        echo "skip a kill while a frame's lasting state is named: gdb could not stop the run there"
    fi
else
    echo "skip a kill while a frame's lasting state is named: no gdb here"
fi
# a stop's own frame off output.every's grid (a shorter run's last, or SIGTERM's) is checked
# for overlaps into the run's summary but not into its step's /stats row, which a resume keeps:
# until 2026-11-30 the row held that check too, where the uninterrupted run's holds only the
# step's contacts, and the hopper in grid mode stopped at step 1606 and resumed had a
# max_overlap of 9.4e-16 there against 4.0e-16 (at 1855, 1.4e-15 against 1.1e-16)
hop=(inputs/hopper.deck --quiet -t 1 --set output.every=10 --set 'run.neighbors="grid"')
bin/nbep run "${hop[@]}" -o $tmp/hop-whole.h5
for stop in 1606 1855; do
    bin/nbep run "${hop[@]}" -n $stop -o $tmp/hop-$stop.h5
    bin/nbep run "${hop[@]}" --resume $tmp/hop-$stop.h5 2>$tmp/hop-$stop.err
    rc=$?
    check "the hopper in grid mode stopped at step $stop and resumed: exit 0 (got $rc), the uninterrupted run's file (/stats too)" \
        "[ $rc = 0 ] && [ ! -s $tmp/hop-$stop.err ] && ck_same $tmp/hop-whole.h5 $tmp/hop-$stop.h5"
done
# a file without that state for its frame (made before 2026-11-30: the datasets deleted here)
# resumes as then: the state afresh, one warning line, also with --quiet, frames that part;
# e = 1 and naive say nothing, nor does a deck that changes e (no uninterrupted run to match).
# From step 600: from 450 or 500 the state made afresh happens to give the same frames since
# the minimum bounce of 2026-12-01 (no sphere held or pressed there whose state it misses)
bin/nbep run "${pile[@]}" -n 600 -o $tmp/pile-old.h5
"$PY" -c "
import h5py
with h5py.File('$tmp/pile-old.h5', 'a') as f:
    del f['checkpoint/contacts'], f['checkpoint/contacts_frame']"
cp $tmp/pile-old.h5 $tmp/pile-other.h5
timeout 120 bin/nbep run "${pile[@]}" -n 950 --resume $tmp/pile-old.h5 2>$tmp/pile-old.err
rc=$?
check "a file without the state resumed from step 600: exit 0 (got $rc), one warning line saying its frames are not the uninterrupted run's bits" \
    "[ $rc = 0 ] && [ \$(wc -l < $tmp/pile-old.err) = 1 ] &&
     grep -q '^nbep: warning: $tmp/pile-old.h5 continues as a predictive run at e < 1 from step 600, .*TC clocks.* not the uninterrupted run.s bits' $tmp/pile-old.err"
check "(and they are not: the state is no formality)" \
    "! h5diff -q $tmp/pile-cells-whole.h5 $tmp/pile-old.h5 /frames >/dev/null 2>&1"
check "(and the resumed part keeps the state again for its frames)" \
    "held_at $tmp/pile-old.h5 950"
# a naive part keeps no such state: its frames' rows say so, and a predictive resume from one
# of them starts the state afresh, saying so, rather than take an older frame's (here the stop's
# own at step 437, in the row that the naive part's frame at step 450 then took)
bin/nbep run "${pile[@]}" -n 437 -o $tmp/pile-naive.h5
bin/nbep run "${pile[@]}" -a naive -n 450 --resume $tmp/pile-naive.h5
timeout 120 bin/nbep run "${pile[@]}" -n 600 --resume $tmp/pile-naive.h5 2>$tmp/pile-naive.err
rc=$?
check "a pile resumed from a naive part's frame at step 450: exit 0 (got $rc), the warning" \
    "[ $rc = 0 ] && grep -q '^nbep: warning: .* from step 450, .*TC clocks' $tmp/pile-naive.err"
# a checkpoint no run wrote (a damaged file, or one edited by hand): an index out of range
# (an event's partner sphere or plane, a resting plane, a contact, a face met) or a time that
# is not finite is refused, exit 2, one line naming the sphere and what, the file as it was
# (until 2026-11-30 the run followed the index out of its arrays)
bin/nbep run "${pile[@]}" -n 750 -o $tmp/pile-stop.h5
damage() { # NAME PYTHON: a copy of the pile stopped at 750, changed by PYTHON (f, row r)
    cp $tmp/pile-stop.h5 $tmp/bad-$1.h5
    "$PY" -c "
import h5py, numpy as np
with h5py.File('$tmp/bad-$1.h5', 'a') as f:
    r = int(f['frames'].attrs['count']) - 1
    k = np.flatnonzero(f['checkpoint/event_kind'][r] == 1)[0]
    $2"
}
damage partner "p = f['checkpoint/event_partner']; row = p[r]; row[k] = 60; p[r] = row"
damage plane "f['checkpoint/event_kind'][r, 5] = 2; f['checkpoint/event_partner'][r, 5] = 6"
damage rest "f['checkpoint/rest'][r, 7] = 9"
damage kind "f['checkpoint/event_kind'][r, 3] = 9"
damage time "f['checkpoint/event_time'][r, k] = np.nan"
damage contact "c = f['checkpoint/contacts']; x = c[r % 2]; i = np.flatnonzero(x['rest_n'] > 0)[0]; x['rest_who'][i, 0] = -1 - i; c[r % 2] = x"
damage face "c = f['checkpoint/contacts']; x = c[r % 2]; x['face_who'][2, 1] = 17; c[r % 2] = x"
# refused NAME LABEL TEXT: the resume of bad-NAME.h5 exits 2 with one line, "its TEXT", and
# leaves the file as it was
refused() {
    local sum
    sum=$(md5sum < $tmp/bad-$1.h5)
    timeout 60 bin/nbep run "${pile[@]}" -n 950 --resume $tmp/bad-$1.h5 2>$tmp/bad.err
    rc=$?
    check "$2: exit 2 (got $rc), one line naming it, the file as it was" \
        "[ $rc = 2 ] && [ \$(wc -l < $tmp/bad.err) = 1 ] &&
         grep -q '^nbep: $tmp/bad-$1.h5: its $3' $tmp/bad.err &&
         [ \"\$(md5sum < $tmp/bad-$1.h5)\" = '$sum' ]"
}
for what in partner:'an event with a sphere' plane:'an event with a plane' rest:'a resting plane' \
            kind:'an event of no kind' time:'an event time that is not finite' \
            contact:'a contact that is not there' face:'a face met that is not there'; do
    refused "${what%%:*}" "a checkpoint giving ${what#*:}" \
        "checkpoint at step 750 gives sphere [0-9]* ${what#*:}"
done
# a frame no run wrote: a position or velocity not finite (until 2026-12-01 a NaN aborted the
# resumed run at its summary's assertion, exit 134, and left the file without its /summary);
# refused the same way
for what in pos-nan:"position'][r]; x[3, 0] = np.nan" vel-inf:"velocity'][r]; x[4, 2] = -np.inf"; do
    field=${what#*:}; field=${field%%\'*}
    damage frame-${what%%:*} "x = f['frames/${what#*:}; f['frames/$field'][r] = x"
    refused frame-${what%%:*} "a frame's ${what%%:*}" "frame at step 750 holds sphere [34] at .* which no run writes"
done
# a sphere flown far past where a deck may place one (an open scene: 5e11 radii a step) is a
# run's own state and resumes (refused as damaged for a day, a reviewer's find)
printf '%s\n' 'run: { steps = 4; dt = 1.0; };' \
    'spheres = ( { position = [0.0, 0.0, 0.0]; velocity = [5e11, 0.0, 0.0]; radius = 1.0; mass = 1.0; } );' \
    >"$tmp/drift.deck"
bin/nbep run "$tmp/drift.deck" --quiet -o "$tmp/drift.h5"
bin/nbep run "$tmp/drift.deck" --quiet -n 6 --resume "$tmp/drift.h5" 2>"$tmp/drift.err"
rc=$?
check "a sphere 2e12 radii from the origin, flown there: the resume runs (exit $rc: $(head -c 200 "$tmp/drift.err"))" \
    "[ $rc = 0 ] && bin/nbep info '$tmp/drift.h5' | grep -q '^frames: .*(last: step 6'"
# a velocity whose energy is beyond doubles: refused before the run, the file as it was
damage frame-vel-huge "x = f['frames/velocity'][r]; x[3, 0] = 1e300; f['frames/velocity'][r] = x"
sum=$(md5sum < $tmp/bad-frame-vel-huge.h5)
timeout 60 bin/nbep run "${pile[@]}" -n 950 --resume $tmp/bad-frame-vel-huge.h5 2>$tmp/bad.err
rc=$?
check "a frame's speed whose energy is beyond doubles: exit 2 (got $rc), one line, the file as it was" \
    "[ $rc = 2 ] && [ \$(wc -l < $tmp/bad.err) = 1 ] &&
     grep -q '^nbep: the spheres. total energy (kinetic inf, .* is beyond doubles' $tmp/bad.err &&
     [ \"\$(md5sum < $tmp/bad-frame-vel-huge.h5)\" = '$sum' ]"
# totals no run wrote (a sum not finite, more quiet steps than steps, a count past 2^62, which
# no run reaches and which the JSON summary's signed 64-bit integers cannot hold once added to:
# until 2026-11-30 a count of 2^63 ran the whole resumed part and then failed, exit 1, two
# lines, "no memory for the JSON summary", the file left without one): refused the same way
for what in energy:"t['energy_initial'] = np.nan" quiet:"t['quiet_steps'] = 751" \
            checks:"t['checks'] = 2**63" collisions:"t['plane_collisions'] = t['sphere_collisions'] = 2**62 + 1"; do
    damage totals-${what%%:*} "t = f['frames/totals'][r]; ${what#*:}; f['frames/totals'][r] = t"
    refused totals-${what%%:*} "totals damaged (${what%%:*})" "totals at step 750 are not a run.s"
done
# totals of another type: a field missing (until 2026-11-30 HDF5 read what the file has and left
# the rest 0, and the resumed run's summary said energy_initial 0 and energy_rel_drift 0, exit 0)
damage totals-fields "t = f['frames/totals'][:]; del f['frames/totals']; keep = ['checks', 'predictions', 'sphere_collisions', 'plane_collisions', 'quiet_steps']; x = np.zeros(len(t), dtype=[(k, '<u8') for k in keep]); [x.__setitem__(k, t[k]) for k in keep]; f.create_dataset('frames/totals', data=x, maxshape=(None,), chunks=True)"
refused totals-fields "totals without energy_initial" "/frames/totals has no field energy_initial"
# the same for the lasting state: its records without the TC clocks' field
damage contacts-fields "c = f['checkpoint/contacts'][:]; t = f['checkpoint/contacts_frame'][:]; del f['checkpoint/contacts']; keep = [k for k in c.dtype.names if k != 't_last']; x = np.zeros(c.shape, dtype=[(k, c.dtype[k]) for k in keep]); [x.__setitem__(k, c[k]) for k in keep]; f.create_dataset('checkpoint/contacts', data=x)"
refused contacts-fields "lasting state without t_last" "/checkpoint/contacts has no field t_last"
bin/nbep run "${cool[@]}" --set physics.restitution=1.0 -n 20 -o $tmp/cool-elastic.h5
bin/nbep run "${cool[@]}" --set physics.restitution=1.0 -n 40 --resume $tmp/cool-elastic.h5 \
    2>$tmp/cool-elastic.err
bin/nbep run $deck "${args[@]}" -a naive --set physics.restitution=0.5 -n 20 -o $tmp/cool-naive.h5
bin/nbep run $deck "${args[@]}" -a naive --set physics.restitution=0.5 -n 40 \
    --resume $tmp/cool-naive.h5 2>$tmp/cool-naive.err
bin/nbep run "${pile[@]}" --set physics.restitution=0.2 -n 700 --resume $tmp/pile-other.h5 \
    2>$tmp/cool-other.err
check "no warning at e = 1, nor for naive at e < 1 (which keeps no such state), nor where the deck changes e (no uninterrupted run to match)" \
    "[ ! -s $tmp/cool-elastic.err ] && [ ! -s $tmp/cool-naive.err ] && [ ! -s $tmp/cool-other.err ] &&
     ! h5ls $tmp/cool-elastic.h5/checkpoint/contacts >/dev/null 2>&1"

# a run that reached run.steps but did not end as completed (a signal during its last step,
# which it finished: its summary says terminated; a kill before its summary was written)
# resumes at no step and ends as completed, its frames and stats as they were, its summary the
# uninterrupted run's (until 2026-11-30 refused, "nothing to resume", and a sweep ran it again
# from step 0). The signal's timing cannot be placed in the last step by a test, so the
# summary is made so by hand.
for how in terminated:"j = json.loads(f['summary'].attrs['json']); j['status'] = 'terminated'; f['summary'].attrs['json'] = json.dumps(j)" \
           killed:"del f['summary'].attrs['json']"; do
    cp $tmp/predictive-whole.h5 $tmp/last-${how%%:*}.h5
    "$PY" -c "
import h5py, json
with h5py.File('$tmp/last-${how%%:*}.h5', 'a') as f:
    ${how#*:}"
    bin/nbep run $deck "${args[@]}" -n 80 --resume $tmp/last-${how%%:*}.h5 \
        --summary $tmp/last-${how%%:*}.json 2>$tmp/last.err
    rc=$?
    check "a run at its last step, ${how%%:*}: resumed at no step, exit 0 (got $rc), completed, the uninterrupted run's summary, frames and stats" \
        "[ $rc = 0 ] && grep -q '\"status\": \"completed\"' $tmp/last-${how%%:*}.json &&
         same_summary $tmp/predictive-whole.json $tmp/last-${how%%:*}.json &&
         h5diff -q $tmp/predictive-whole.h5 $tmp/last-${how%%:*}.h5 /frames &&
         h5diff -q $tmp/predictive-whole.h5 $tmp/last-${how%%:*}.h5 /stats"
done
# nothing to resume: run.steps at or before the file's last frame is refused with exit 2, the
# file left as it was (it was given a zero-step summary, and its root `steps` the smaller count)
sum=$(md5sum < $tmp/predictive-whole.h5)
for n in 80 50; do
    bin/nbep run $deck "${args[@]}" -n $n --resume $tmp/predictive-whole.h5 2>$tmp/nothing.err
    rc=$?
    check "a resume of a file at step 80 with run.steps = $n is refused with exit 2 (got $rc)" \
        "[ $rc = 2 ] && grep -q 'nothing to resume: its last frame is at step 80 and run.steps is $n' \
         $tmp/nothing.err"
    check "the refused resume leaves the file as it was" \
        "[ \"\$(md5sum < $tmp/predictive-whole.h5)\" = '$sum' ]"
done

# killed by SIGTERM at an arbitrary step of a very long run, then resumed to a fixed end past
# that step; compared with one uninterrupted run to the same end (no assumption on how far the
# killed run got: that depends on the machine)
bin/nbep run $deck "${args[@]}" -n 100000000 -o $tmp/killed.h5 &
pid=$!
for _ in $(seq 300); do [ -s $tmp/killed.h5 ] && break; sleep 0.1; done
sleep 0.5
kill -TERM $pid
wait $pid 2>/dev/null
check "SIGTERM stops the long run with 143" "[ $? = 143 ]"
last=$(bin/nbep info $tmp/killed.h5 | sed -n 's/^frames: .*last: step \([0-9]*\).*/\1/p')
check "it got somewhere (step $last)" "[ -n '$last' ] && [ '$last' -gt 0 ]"
check "its summary says terminated, short of the 100000000 steps requested" \
    "bin/nbep info $tmp/killed.h5 | grep -Eqx 'status: +terminated \\(SIGTERM, SIGHUP, SIGUSR1 or SIGUSR2\\): step $last of 100000000'"
end=$(( ${last:-0} + 200 ))
bin/nbep run $deck "${args[@]}" -n $end -o $tmp/whole.h5 --summary $tmp/whole.json
bin/nbep run $deck "${args[@]}" -n $end --resume $tmp/killed.h5 --summary $tmp/resumed.json \
    2>/dev/null
check "resumed after SIGTERM, every frame equals the uninterrupted run's" \
    "same_frames $tmp/whole.h5 $tmp/killed.h5"
check "and its summary is the uninterrupted run's" "same_summary $tmp/whole.json $tmp/resumed.json"
# the resumed run's summary (the file's, and --summary's) says how it ended: completed, the
# step reached being the one requested
check "the resumed run's summary says completed, step $end of $end" \
    "bin/nbep info $tmp/killed.h5 | grep -Eqx 'status: +completed: step $end of $end' &&
     $PY -c 'import json, sys; s = json.load(open(sys.argv[1])); sys.exit(not (s[\"status\"] == \"completed\" and s[\"steps\"] == s[\"steps_requested\"] == int(sys.argv[2])))' $tmp/resumed.json $end"

# a deck that does not match the file is refused, naming both
bin/nbep run $deck --quiet --set spheres.[0].count=401 --set box.max=[2,2,2] -n 80 \
    --resume $tmp/predictive-part.h5 2>$tmp/mismatch.err
rc=$?
check "a different deck is refused with exit 2 (got $rc)" "[ $rc = 2 ]"
check "the refusal says what differs" "grep -q 'holds 400 spheres' $tmp/mismatch.err"
# the same counts but other radii or masses: refused too, naming what differs (README: resume
# checks counts, radii and masses)
for what in radius mass; do
    val=$([ $what = radius ] && echo 0.051 || echo 1.5)
    bin/nbep run $deck --quiet --set spheres.[0].count=400 --set box.max=[2,2,2] \
        --set spheres.[0].$what=$val -n 80 --resume $tmp/predictive-part.h5 2>$tmp/mismatch-$what.err
    rc=$?
    check "a deck with another $what is refused with exit 2 (got $rc)" "[ $rc = 2 ]"
    check "the refusal names the $what" "grep -q '$what' $tmp/mismatch-$what.err"
done
# the same spheres under another dt, gravity or walls: refused too, the file left as it was
# (its event slots were predicted under them, and a frame's time is its step times dt: resumed
# with another dt, a run's clock and its slots' times disagreed and spheres passed through each
# other); another restitution is taken (it acts only when an event comes)
sum=$(md5sum < $tmp/predictive-part.h5)
for case in "run.dt=0.002|run.dt = 0.001 but" \
    "physics.gravity=[0.0,0.0,-9.8]|accelerations (physics.gravity) of /spheres/acceleration" \
    "box.max=[2.0,2.0,2.5]|was run in another box than"; do
    set_=${case%%|*} want=${case#*|}
    box=$([ "${set_%%=*}" = box.max ] && echo "$set_" || echo "box.max=[2,2,2]")
    bin/nbep run $deck --quiet --set spheres.[0].count=400 --set "$box" --set "$set_" -n 90 \
        --resume $tmp/predictive-part.h5 2>$tmp/mismatch-other.err
    rc=$?
    check "a deck with $set_ is refused with exit 2 (got $rc)" "[ $rc = 2 ]"
    check "the refusal says '$want'" "grep -qF '$want' $tmp/mismatch-other.err"
    check "the refused resume leaves the file as it was" \
        "[ \"\$(md5sum < $tmp/predictive-part.h5)\" = '$sum' ]"
done
# a plane of the deck's own, moved or turned
bin/nbep run inputs/bounce.deck --quiet -n 40 -o $tmp/bounce-part.h5
sum=$(md5sum < $tmp/bounce-part.h5)
for case in "planes.[0].point=[0.0,0.0,0.01]|offsets of /planes/offset" \
    "planes.[0].normal=[0.0,0.1,1.0]|normals of /planes/normal"; do
    set_=${case%%|*} want=${case#*|}
    bin/nbep run inputs/bounce.deck --quiet --set "$set_" -n 80 --resume $tmp/bounce-part.h5 \
        2>$tmp/mismatch-other.err
    rc=$?
    check "a deck with $set_ is refused with exit 2 (got $rc)" "[ $rc = 2 ]"
    check "the refusal says '$want'" "grep -qF '$want' $tmp/mismatch-other.err"
    check "the refused resume leaves the file as it was" \
        "[ \"\$(md5sum < $tmp/bounce-part.h5)\" = '$sum' ]"
done
# files edited by hand: a dataset longer than the deck's (read only after its size is checked:
# it overran the buffer), box attributes on a run whose deck has no box, and a file without
# them (made before they were written: its box is not checked)
"$PY" - $tmp/bounce-part.h5 $tmp/bounce-long.h5 $tmp/bounce-boxed.h5 <<'PYEOF'
import shutil, sys, h5py, numpy as np
src, long_, boxed = sys.argv[1:4]
shutil.copy(src, long_)
shutil.copy(src, boxed)
with h5py.File(long_, "r+") as f:
    a = f["spheres/acceleration"][:]
    del f["spheres/acceleration"]
    f["spheres/acceleration"] = np.tile(a, (200, 1))
with h5py.File(boxed, "r+") as f:
    f.attrs["box_min"] = np.zeros(3)
    f.attrs["box_max"] = np.ones(3)
PYEOF
bin/nbep run inputs/bounce.deck --quiet -n 80 --resume $tmp/bounce-long.h5 2>$tmp/long.err
rc=$?
check "a file with a longer /spheres/acceleration is refused with exit 2 (got $rc)" \
    "[ $rc = 2 ] && grep -q 'acceleration holds 600 values where .* makes 3' $tmp/long.err"
bin/nbep run inputs/bounce.deck --quiet -n 80 --resume $tmp/bounce-boxed.h5 2>$tmp/boxed.err
rc=$?
check "a file with a box resumed by a deck without one is refused with exit 2 (got $rc)" \
    "[ $rc = 2 ] && grep -q 'was run in another box than' $tmp/boxed.err"
cp $tmp/predictive-part.h5 $tmp/no-box.h5
"$PY" -c "import h5py, sys; f = h5py.File(sys.argv[1], 'r+'); del f.attrs['box_min']; \
del f.attrs['box_max']" $tmp/no-box.h5
bin/nbep run $deck --quiet --set spheres.[0].count=400 --set box.max=[2,2,2] -n 90 \
    --resume $tmp/no-box.h5
rc=$?
check "a file without box attributes resumes (got $rc), and nbep info prints no box" \
    "[ $rc = 0 ] && ! bin/nbep info $tmp/no-box.h5 | grep -q '^box:'"
bin/nbep run $deck --quiet --set spheres.[0].count=400 --set box.max=[2,2,2] \
    --set physics.restitution=0.9 -n 90 --resume $tmp/predictive-part.h5
rc=$?
check "a deck with another restitution resumes (got $rc)" "[ $rc = 0 ]"

# an exact run that ends with overlaps far past round-off says so, also with --quiet, and
# completes (README, Checking a run): the two spheres of the example, one moved into the other
# in the file's last frame (0.38 deep, 1.9 of the smaller radius) and the run resumed from it
# (no collision: they were already past contact). The same run unchanged, and naive's run of
# the paper's box at a coarse dt (overlaps of 0.4 radii, by design), say nothing.
bin/nbep run inputs/two-spheres.deck --quiet -n 10 -o $tmp/moved.h5
"$PY" -c "import h5py, sys; p = h5py.File(sys.argv[1], 'r+')['frames/position']; a = p[-1]
a[0] = [a[1][0] - 0.3, a[1][1], 0.0]; p[-1] = a" $tmp/moved.h5
bin/nbep run inputs/two-spheres.deck --quiet -n 100 --resume $tmp/moved.h5 2>$tmp/moved.err
rc=$?
check "an exact run ending in overlaps: exit 0 (got $rc), one warning line naming the overlap" \
    "[ $rc = 0 ] && [ \$(wc -l <$tmp/moved.err) = 1 ] &&
     grep -q '^nbep: warning: spheres overlapped by up to 1.9 of the smaller radius .* in $tmp/moved.h5' $tmp/moved.err"
bin/nbep run inputs/two-spheres.deck --quiet -n 10 -o $tmp/kept.h5
bin/nbep run inputs/two-spheres.deck --quiet -n 100 --resume $tmp/kept.h5 2>$tmp/kept.err
bin/nbep run $deck --quiet -a naive -n 20 --dt 0.01 --set spheres.[0].count=1000 \
    -o $tmp/coarse.h5 --summary $tmp/coarse.json 2>$tmp/coarse.err
check "no warning for the file unchanged, nor for naive's overlaps by design" \
    "[ ! -s $tmp/kept.err ] && [ ! -s $tmp/coarse.err ] &&
     grep -q '\"max_overlap_rel\": 0\.[1-9]' $tmp/coarse.json"
# naive's file resumed by the exact algorithm: the overlaps are the naive part's, and the
# warning says so rather than blame the predictive part (until 2026-12-04, a review's)
bin/nbep run $deck --quiet -n 22 --dt 0.01 --set spheres.[0].count=1000 --resume $tmp/coarse.h5 \
    2>$tmp/coarse-pred.err
rc=$?
check "naive's file resumed by predictive: exit 0 (got $rc), one warning naming the earlier part's algorithm" \
    "[ $rc = 0 ] && [ \$(wc -l <$tmp/coarse-pred.err) = 1 ] &&
     grep -q '^nbep: warning: spheres overlapped by up to 0\.[1-9].*; an earlier part of the run ran another algorithm, whose overlaps this part starts from: ' $tmp/coarse-pred.err"
# a predictive file with a naive part in the middle, resumed by predictive again: the
# overlaps are still the naive part's (until 2026-12-04 only the first part's algorithm was
# compared, and this warning blamed the predictive part)
bin/nbep run $deck --quiet -n 2 --dt 0.01 --set spheres.[0].count=1000 -o $tmp/middle.h5 &&
    bin/nbep run $deck --quiet -a naive -n 20 --dt 0.01 --set spheres.[0].count=1000 \
        --resume $tmp/middle.h5 2>$tmp/middle-naive.err
bin/nbep run $deck --quiet -n 22 --dt 0.01 --set spheres.[0].count=1000 --resume $tmp/middle.h5 \
    2>$tmp/middle-pred.err
rc=$?
check "a naive part between predictive ones: exit 0 (got $rc), the warning names the earlier part's algorithm" \
    "[ $rc = 0 ] && [ ! -s $tmp/middle-naive.err ] && [ \$(wc -l <$tmp/middle-pred.err) = 1 ] &&
     grep -q '^nbep: warning: spheres overlapped by up to 0\.[1-9].*; an earlier part of the run ran another algorithm, whose overlaps this part starts from: ' $tmp/middle-pred.err"
check "a file whose parts all ran predictive: the overlap warning names no other algorithm" \
    "! grep -q 'another algorithm' $tmp/moved.err"
# Far from the origin, round-off is the coordinates' (run.c EXACT_OVERLAP_ULPS): a sphere
# dropped onto a floor 1e11 radii out overlaps it by 1 to 4 of their ulps (1.5e-5 to 6.1e-5
# of a radius) in each neighbour mode, and gets no warning (until 2026-12-03 it did); a
# sphere that flies 11 radii to a wall 5e11 radii out in all-pairs mode (11000 steps, each
# rounding its position) overlaps it by 0.24 of a radius, past the 0.0036 its coordinates
# explain, and does, the bound named.
cat >$tmp/far-floor.deck <<'EOF'
run: { steps = 1000; dt = 0.001; threads = 1; };
physics: { gravity = [0.0, 0.0, -9.81]; restitution = 0.5; };
planes = ( { normal = [0.0, 0.0, 1.0]; point = [0.0, 0.0, 1e11]; } );
spheres = ( { position = [0.0, 0.0, 100000000001.5]; velocity = [0.0, 0.0, 0.0]; radius = 1.0; mass = 1.0; } );
output: { every = 1000; };
EOF
cat >$tmp/far-wall.deck <<'EOF'
run: { steps = 12000; dt = 0.001; threads = 1; };
planes = ( { normal = [-1.0, 0.0, 0.0]; point = [500000000011.0, 0.0, 0.0]; } );
spheres = ( { position = [500000000000.0, 0.0, 0.0]; velocity = [1.01318, 0.0, 0.0]; radius = 1.0; mass = 1.0; } );
output: { every = 12000; };
EOF
for mode in all grid cells; do
    bin/nbep run $tmp/far-floor.deck --quiet --set "run.neighbors=\"$mode\"" \
        -o $tmp/far-floor.h5 --summary $tmp/far-floor.json 2>$tmp/far-floor.err
    rc=$?
    check "$mode: a floor 1e11 radii out, overlaps of its coordinates' round-off: exit 0 (got $rc), no warning" \
        "[ $rc = 0 ] && [ ! -s $tmp/far-floor.err ] &&
         grep -q '\"plane_collisions\": [1-9]' $tmp/far-floor.json &&
         grep -q '\"max_overlap_rel\": [1-9][.0-9]*e-05' $tmp/far-floor.json"
done
bin/nbep run $tmp/far-wall.deck --quiet -o $tmp/far-wall.h5 2>$tmp/far-wall.err
rc=$?
check "a wall 5e11 radii out, reached after 11000 steps: exit 0 (got $rc), one warning with the coordinates' bound" \
    "[ $rc = 0 ] && [ \$(wc -l <$tmp/far-wall.err) = 1 ] &&
     grep -q '^nbep: warning: spheres overlapped by up to 0.2[0-9]* of the smaller radius .* in $tmp/far-wall.h5, .*(below 1e-9; with coordinates this far from the origin, below 0.0036)' $tmp/far-wall.err"
# naive at a run.dt where spheres pass through each other (overlaps of several radii, no
# gravity so that the overlaps' projection adds no energy): the other warning, exit 0
bin/nbep run $deck --quiet -a naive -n 4 --dt 0.5 --set 'physics.gravity=[0,0,0]' \
    -o $tmp/through.h5 2>$tmp/through.err
rc=$?
check "naive with overlaps past a radius: exit 0 (got $rc), one warning naming naive and run.dt" \
    "[ $rc = 0 ] && [ \$(wc -l <$tmp/through.err) = 1 ] &&
     grep -q '^nbep: warning: spheres overlapped by up to [0-9.]* of the smaller radius .* in $tmp/through.h5: naive finds contacts after they overlap, and at this run.dt spheres passed into and through each other or the planes (collisions missed); a smaller run.dt, or the predictive algorithm, avoids it' $tmp/through.err"
# step order in a periodic box at a run.dt where spheres pass through each other: its own
# words and cure (run.order = "time"), no planes named where there are none (until 2026-12-05
# naive's words, "or the planes", and "the predictive algorithm", which it already is)
bin/nbep run inputs/hard-sphere-fluid.deck --quiet -n 4 --dt 0.5 --set 'run.order="step"' \
    --set 'run.neighbors="all"' --set spheres.[0].count=512 --set 'box.max=[9.6,9.6,9.6]' \
    -o $tmp/step-through.h5 2>$tmp/step-through.err
rc=$?
check "step order with overlaps past a radius, periodic: exit 0 (got $rc), one warning naming step order and its cure, no planes ($(head -c 300 $tmp/step-through.err))" \
    "[ $rc = 0 ] && [ \$(wc -l <$tmp/step-through.err) = 1 ] &&
     grep -q '^nbep: warning: spheres overlapped by up to [0-9.]* of the smaller radius .* in $tmp/step-through.h5: run.order = \"step\" reacts to a step.s events at once, some shadowed by others, and at this run.dt spheres passed into and through each other (collisions missed); a smaller run.dt, or run.order = \"time\" (exact), avoids it (README, Accuracy)\$' $tmp/step-through.err"
test_end resume
