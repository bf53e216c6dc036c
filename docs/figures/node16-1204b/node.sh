#!/usr/bin/env bash
# The seventh loan of a 16-core node (2026-12-04, at 3a7fc7b), one call: the table of issue 8
# (docs/figures/node16-1130/run.sh: nbep on 1, 2, 4, 8 and 16 threads beside EDMD Single on the
# three dense fluids, 3 repeats, then the paper's box in its three predictive modes), then the
# team loop's A/B prepared at the sixth loan and not run there (docs/figures/node16-1204/ab.sh:
# 986178f against this build, 2, 4 and 16 threads). Prepared here with
#   EDMD=/work/scratch/edmd bash docs/figures/node16-e053a30/prep.sh
#   cp OLD-986178f/bin/nbep build/dev/nbep.old; cp build/dev/kit/nbep.bin build/dev/nbep.new
# and run there, build/dev carried:  OUT=$OUT bash docs/figures/node16-1204b/node.sh (this file
# as it stands; the loan's call wrote straight into $OUT, and table.log kept the rows)
set -u
cd "$(dirname "$0")/../../.." || exit 1
# the rows go to a folder of their own, and $OUT gets one archive of it and the two logs' tails: a
# loan returns 8 files of $OUT at most (the first call returned the logs, not rows.csv)
R=/tmp/node-out
mkdir -p "$R/table" "$R/ab" "${OUT:-/tmp/out}"
OUT=$R/table REPS=${REPS:-3} LIMIT=${LIMIT:-150} bash docs/figures/node16-1130/run.sh >"$R/table.log" 2>&1
OUT=$R/ab REPS=20 LIMIT=${AB_LIMIT:-70} bash docs/figures/node16-1204/ab.sh >"$R/ab.log" 2>&1
tail -n 3 "$R/table/log.txt" "$R/ab/log.txt"
tar czf "${OUT:-/tmp/out}/all.tgz" -C "$R" table ab table.log ab.log
