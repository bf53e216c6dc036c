#!/usr/bin/env bash
# A disk that fills up during a run: one clear line naming the file, exit status 1, and every
# frame written before it still readable. Uses a small tmpfs, so it needs root (CI runs as
# root); elsewhere it says so and exits 77, which scripts/run-tests.sh counts as a skip.
. "$(dirname "$0")/lib.sh"
mnt=build/tests/tmp/diskfull
mkdir -p "$mnt"
if [ "$(id -u)" != 0 ] || ! mount -t tmpfs -o size=3m tmpfs "$mnt" 2>/dev/null; then
    echo "SKIP diskfull: cannot mount a small tmpfs here (needs root)"
    exit 77  # counted as a skip by scripts/run-tests.sh, never as a pass
fi
trap 'umount "$mnt" 2>/dev/null' EXIT
# 4096 spheres: a frame with positions, velocities and event slots is about 270 kB, so 3 MB
# fill up after about ten frames of the 41 asked for
# (the JSON summary goes beside the small disk, where there is room for it)
rm -f "$mnt/../diskfull.json"
bin/nbep run inputs/paper-box.deck --quiet -n 400 -o "$mnt/full.h5" \
    --summary "$mnt/../diskfull.json" 2>"$mnt/../diskfull.err"
rc=$?
err=$mnt/../diskfull.err
check "a full disk ends the run with exit 1 (got $rc)" "[ $rc = 1 ]"
check "with one line on stderr" "[ \$(wc -l < '$err') = 1 ]"
check "that names the file and the reason: the frame it kept room for ($(cat "$err"))" \
    "grep -q '$mnt/full.h5: no room for frame [0-9]* (step [0-9]*) (.*): No space left on device; the frames before it are kept' '$err'"
bin/nbep info "$mnt/full.h5" >"$mnt/../diskfull.info" 2>&1
check "the file still opens" "[ \$? = 0 ]"
check "with the frames written before the disk filled" \
    "grep -Eq '^frames: +([2-9]|[1-9][0-9])' '$mnt/../diskfull.info'"
# a script reading the summaries of many runs tells this one from a complete one
check "the JSON summary says failed, its steps fewer than the 400 requested" \
    "$PY -c 'import json, sys; s = json.load(open(sys.argv[1])); sys.exit(not (s[\"status\"] == \"failed\" and s[\"steps_requested\"] == 400 and s[\"steps\"] < 400))' '$mnt/../diskfull.json'"
check "the file has no summary (the disk had no room), and nbep info says the status is unknown" \
    "grep -Eq '^status: +unknown \\(no summary' '$mnt/../diskfull.info'"
"$PY" - "$mnt/full.h5" <<'PYEOF' && echo "ok   every counted frame reads back" || { echo "FAIL every counted frame reads back"; fail=1; }
import sys, h5py, numpy as np
f = h5py.File(sys.argv[1], "r")
n = int(f["frames"].attrs["count"])
pos = f["frames/position"][:n]
assert np.isfinite(pos).all() and n >= 2
assert (f["frames/step"][:n] == np.arange(n) * 10).all()
PYEOF
# A sweep's run goes through the same pipeline as `nbep run`: its row holds that one error,
# not the cascade of failing closes that follows it.
rm -f "$mnt/full.h5" "$mnt/full.xmf"
{ cat inputs/paper-box.deck
  echo 'sweep: { replicas = 1; vary = ( { key = "run.steps"; values = [400]; } ); };'
} >"$mnt/../diskfull-sweep.deck"
bin/nbep sweep "$mnt/../diskfull-sweep.deck" --quiet -o "$mnt/s.h5" 2>"$mnt/../diskfull-sweep.err"
rc=$?
line=$(grep 'sweep run 0' "$mnt/../diskfull-sweep.err")
check "a sweep run on a full disk fails the sweep (exit 1, got $rc)" "[ $rc = 1 ]"
check "its row names the run's file and the reason" \
    "echo \"\$line\" | grep -q 's.sweep/run-0000.h5: .*No space left'"
check "with that one error, as nbep run reports it, under the line's one prefix: $line" \
    "! echo \"\$line\" | grep -q '; nbep:' && echo \"\$line\" | grep -q '^nbep: sweep run 0 (run.steps=400 seed=1) failed: [^n]'"
# the room the run kept ahead of its file goes back at its close (reserve_room, output.c): the
# study's tables fit there, and they hold the failed run's error
check "the study's tables are written, the run's row naming its error" \
    "grep -q 'No space left on device' '$mnt/s.sweep/summary.csv' && [ -s '$mnt/s.sweep/summary.h5' ]"
check "the last line points to them: $(tail -n 1 "$mnt/../diskfull-sweep.err")" \
    "tail -n 1 '$mnt/../diskfull-sweep.err' | grep -q '^nbep: sweep: 0 of 1 runs complete, 1 failed (run 0; errors in $mnt/s.sweep/summary.csv)\$'"
# a disk full to its last byte before the study starts: no room for its tables either, and the
# one made empty is not left, nor does the last line send the user to a table that is not
# there (until 2026-12-01 it did, and summary.h5.partial stayed)
rm -rf "$mnt/s.sweep" "$mnt/full.h5" "$mnt/full.xmf"
mkdir -p "$mnt/s.sweep"
dd if=/dev/zero of="$mnt/filler" bs=64k 2>/dev/null
dd if=/dev/zero of="$mnt/filler2" bs=1 2>/dev/null
bin/nbep sweep "$mnt/../diskfull-sweep.deck" --quiet -o "$mnt/s.h5" 2>"$mnt/../diskfull-sweep.err"
rc=$?
check "a sweep on a disk full from the start fails (exit 1, got $rc)" "[ $rc = 1 ]"
check "no summary table left half-made" "[ -z \"\$(ls '$mnt/s.sweep' | grep summary)\" ]"
check "the last line says the failed runs' errors are above: $(tail -n 1 "$mnt/../diskfull-sweep.err")" \
    "tail -n 1 '$mnt/../diskfull-sweep.err' | grep -q '^nbep: sweep: 0 of [0-9]* runs complete, [0-9]* failed (run 0.*; errors above: no summary table could be written)\$'"
rm -f "$mnt/filler" "$mnt/filler2"
# Few spheres and many frames: the sidecar (about 1.4 kB a frame, rewritten whole) outgrows the
# file. The room kept ahead counts its next rewrite, so the disk is met at a frame's
# reservation, as above, not at a rewrite (until 2026-12-04 the run ended with `cannot write
# the XDMF sidecar: No space left on device` at frame 512), and the close's rewrite lists every
# frame the file kept. The disk's 2.75 MB lie where a room without the sidecar's part would pass
# frame 1024's reservation (the file 0.85 MB, the sidecar 0.71 MB, the room 0.9 MB) and then
# fail the rewrite that lists those 1024 frames (1.42 MB beside the old sidecar).
umount "$mnt" && mount -t tmpfs -o size=2816k tmpfs "$mnt"
bin/nbep run inputs/two-spheres.deck --quiet --set output.every=1 -n 5000 -o "$mnt/xs.h5" \
    2>"$mnt/../diskfull-xmf.err"
rc=$?
check "a full disk met by a run of many small frames: exit 1 (got $rc), one line: $(cat "$mnt/../diskfull-xmf.err")" \
    "[ $rc = 1 ] && [ \$(wc -l < '$mnt/../diskfull-xmf.err') = 1 ] &&
     grep -q '^nbep: $mnt/xs.h5: no room for frame [0-9]* (step [0-9]*) (.*): No space left on device; the frames before it are kept\$' '$mnt/../diskfull-xmf.err'"
"$PY" - "$mnt/xs.h5" "$mnt/xs.xmf" <<'PYEOF' && echo "ok   the sidecar lists every frame the file kept" || { echo "FAIL the sidecar lists every frame the file kept"; fail=1; }
import sys, h5py, xml.etree.ElementTree as ET
f = h5py.File(sys.argv[1], "r")
n = int(f["frames"].attrs["count"])
grids = ET.parse(sys.argv[2]).getroot().findall(".//Grid/Grid")
assert n >= 256 and len(grids) == n, (n, len(grids))
assert [g.get("Name") for g in grids] == ["step %d" % s for s in f["frames/step"][:n]]
PYEOF
# A new run into a file of an older run, stopped for room at its first frame (a fluid of 32000:
# its layout, 1.3 MB, fits the disk, its first frame's room, 3.4 MB, does not): its file took
# the older one's place as the run began, and the older one's sidecar, which names 2 spheres
# and 21 frames, goes with it (until 2026-12-05 it stayed beside the new file)
umount "$mnt" && mount -t tmpfs -o size=3m tmpfs "$mnt"
bin/nbep run inputs/two-spheres.deck --quiet -n 20 --set output.every=1 -o "$mnt/old.h5"
rc0=$?
bin/nbep run inputs/hard-sphere-fluid.deck --quiet -n 20 -o "$mnt/old.h5" 2>"$mnt/../old.err"
rc=$?
check "a run stopped for room at its first frame: exit 1 (got $rc; the older run's $rc0), its sidecar gone with the older file: $(cat "$mnt/../old.err")" \
    "[ $rc0 = 0 ] && [ $rc = 1 ] && grep -q '^nbep: $mnt/old.h5: no room for frame 0 ' '$mnt/../old.err' &&
     [ ! -e '$mnt/old.xmf' ] && bin/nbep info '$mnt/old.h5' | grep -Eq '^spheres: +32000\$'"
# a read-only file system is the user's path, as one without permission: a run into it and a
# sweep over a study on it (whose last tables it cannot remove) exit 2 with one line (until
# 2026-12-01 both gave 1, a run-time failure)
umount "$mnt" && mount -t tmpfs -o size=3m tmpfs "$mnt"
{ cat inputs/two-spheres.deck
  echo 'sweep: { replicas = 1; vary = ( { key = "run.steps"; values = [10]; } ); };'
} >"$mnt/../ro-sweep.deck"
bin/nbep sweep "$mnt/../ro-sweep.deck" --quiet -o "$mnt/ro.h5" 2>/dev/null
rc0=$?
mount -o remount,ro "$mnt"
bin/nbep run inputs/two-spheres.deck --quiet -o "$mnt/x.h5" 2>"$mnt/../ro-run.err"
rc1=$?
bin/nbep sweep "$mnt/../ro-sweep.deck" --quiet -o "$mnt/ro.h5" 2>"$mnt/../ro-sweep.err"
rc2=$?
check "a read-only file system: a run into it exits 2 (got $rc1), one line: $(cat "$mnt/../ro-run.err")" \
    "[ $rc0 = 0 ] && [ $rc1 = 2 ] && [ \$(wc -l < '$mnt/../ro-run.err') = 1 ] &&
     grep -qi 'read-only file system' '$mnt/../ro-run.err'"
check "... and a sweep over a study on it exits 2 (got $rc2), one line: $(cat "$mnt/../ro-sweep.err")" \
    "[ $rc2 = 2 ] && [ \$(wc -l < '$mnt/../ro-sweep.err') = 1 ] &&
     grep -q 'cannot remove the last sweep.s .*summary.csv: Read-only file system' '$mnt/../ro-sweep.err'"
test_end diskfull
