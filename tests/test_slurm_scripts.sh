#!/usr/bin/env bash
# The Slurm job scripts (scripts/*.sbatch) as a cluster's shell runs them:
#   - under `set -u`, an array that may be empty expands as ${a[@]+"${a[@]}"}: a plain
#     "${a[@]}" of an empty array is an "unbound variable" error on bash before 4.4 (CentOS 7,
#     RHEL 7, still on many clusters' nodes), so slurm-scaling.sbatch without extra options
#     died at its first `nbep check` there (this machine's bash 5 cannot show it, hence the
#     look at the text);
#   - run by hand outside Slurm, as README says (Running on a cluster): slurm-run.sbatch
#     runs the deck, slurm-scaling.sbatch writes its CSV (one thread, one rank: no mpirun).
# Run from anywhere after `make`; exit status 1 when a check fails.
. "$(dirname "$0")/lib.sh"
test_tmp slurm_scripts

for s in scripts/*.sbatch; do
    # code lines only (comments may show the bare form), "${name[@]}" not after a "+"
    bare=$(grep -nE '(^|[^+])"\$\{[A-Za-z_][A-Za-z0-9_]*\[@\]\}"' "$s" | grep -vE '^[0-9]+:[[:space:]]*#')
    check "$s: every array expansion guarded for bash before 4.4 under set -u${bare:+ (not: $bare)}" \
        "[ -z \"\$bare\" ]"
done

NBEP=$PWD/bin/nbep timeout -k 5 60 bash scripts/slurm-run.sbatch inputs/two-spheres.deck \
    -n 20 --quiet -o "$tmp/run.h5" >"$tmp/run.out" 2>&1
rc=$?
check "slurm-run.sbatch by hand: exit 0 and the run's file (got $rc)" \
    "[ $rc = 0 ] && [ -s '$tmp/run.h5' ]"

# WORK a folder of the user's (WORK=$SCRATCH): the script works in a folder of its own inside
# it and deletes only that (until 2026-12-01 it deleted WORK whole, the user's files too)
mkdir -p "$tmp/work"
echo keep >"$tmp/work/mine.txt"
NBEP=$PWD/bin/nbep SPHERES=64 STEPS=5 RUNS=2 THREADS_LIST=1 RANKS_LIST=1 OUT="$tmp/scaling.csv" \
    WORK="$tmp/work" timeout -k 5 120 bash scripts/slurm-scaling.sbatch >"$tmp/scaling.out" 2>&1
rc=$?
check "slurm-scaling.sbatch by hand, no extra options: exit 0, a header and 4 rows (got $rc)" \
    "[ $rc = 0 ] && [ \$(wc -l <'$tmp/scaling.csv') = 5 ] &&
     head -1 '$tmp/scaling.csv' | grep -q '^study,kind,ranks,threads,' &&
     [ \$(grep -c '^threads,' '$tmp/scaling.csv') = 2 ] && [ \$(grep -c '^ranks,' '$tmp/scaling.csv') = 2 ]"
check "... WORK kept with the user's file in it, nothing of the script's left there" \
    "grep -qx keep '$tmp/work/mine.txt' && [ \"\$(ls -A '$tmp/work')\" = mine.txt ]"
# a job on more than one node: the run files go in the submit folder, which every node sees,
# not in TMPDIR, node-local on most clusters (until 2026-12-03: the sweep's ranks on other
# nodes failed every run)
mkdir -p "$tmp/submit" "$tmp/nodelocal"
at=$(cd "$tmp" && pwd) # the script works in the submit folder: paths from the root
NBEP=$PWD/bin/nbep SPHERES=64 STEPS=5 RUNS=2 THREADS_LIST=1 RANKS_LIST=1 OUT="$at/nodes.csv" \
    SLURM_JOB_NUM_NODES=2 SLURM_SUBMIT_DIR="$at/submit" TMPDIR="$at/nodelocal" \
    timeout -k 5 120 bash scripts/slurm-scaling.sbatch "$PWD/inputs/paper-box.deck" \
    >"$tmp/nodes.out" 2>&1
rc=$?
check "slurm-scaling.sbatch on 2 nodes: exit 0 (got $rc), 4 rows, run files in the submit folder: $(head -1 "$tmp/nodes.out")" \
    "[ $rc = 0 ] && [ \$(wc -l <'$tmp/nodes.csv') = 5 ] &&
     grep -q '^slurm-scaling.sbatch: run files in $at/submit/nbep-scaling\.' '$tmp/nodes.out' &&
     [ -z \"\$(ls -A '$tmp/submit')\" ]"
# the options the script sets for each run, among the user's: refused before any run (a user's
# -n won over STEPS and the CSV's steps were wrong; -o and --summary were overridden silently)
# (attached forms and the --set keys they stand for too: a review found -n7, -t3 and --set
# run.steps=7 passed)
for opt in "-n 7" --steps=7 "-o x.h5" "--summary x.json" -n7 -t3 "--set run.steps=7" \
    "--set output.file=x.h5" "--set sweep.replicas=2" "--set spheres.[0].count=9" \
    "--set spheres[0].count=9"; do
    # shellcheck disable=SC2086 # the option's words
    NBEP=$PWD/bin/nbep SPHERES=64 STEPS=5 RUNS=2 THREADS_LIST=1 RANKS_LIST=1 \
        OUT="$tmp/refused.csv" WORK="$tmp/work" timeout -k 5 60 \
        bash scripts/slurm-scaling.sbatch inputs/paper-box.deck --quiet $opt \
        >"$tmp/refused.out" 2>&1
    rc=$?
    case $opt in "--set "*) last=${opt#--set } ;; *) last=${opt%% *} ;; esac
    check "slurm-scaling.sbatch with the user's $opt: exit 2 (got $rc), one line naming it, no CSV" \
        "[ $rc = 2 ] && [ \$(wc -l <'$tmp/refused.out') = 1 ] &&
         grep -qF 'slurm-scaling.sbatch: $last is the script' '$tmp/refused.out' && [ ! -e '$tmp/refused.csv' ]"
done
NBEP=$PWD/bin/nbep SPHERES=64 STEPS=5 RUNS=2 THREADS_LIST=1 RANKS_LIST=1 OUT="$tmp/taken.csv" \
    WORK="$tmp/work" timeout -k 5 120 bash scripts/slurm-scaling.sbatch inputs/paper-box.deck \
    --set physics.restitution=0.9 --dt 0.002 >"$tmp/taken.out" 2>&1
rc=$?
check "... and other options taken (--set physics.restitution=0.9 --dt 0.002: exit $rc, 4 rows)" \
    "[ $rc = 0 ] && [ \$(wc -l <'$tmp/taken.csv') = 5 ]"
# a --set of a whole group holding one of the script's own settings: the script's still win, as
# nbep takes options in order and the user's come first (until 2026-12-05 they came last, and
# --set 'run={...}' put back the default 1000 steps where the CSV said STEPS). The wrapper
# writes each run's steps and spheres, from its summary, beside the CSV's rows.
cat >"$tmp/nbep-logged" <<END
#!/usr/bin/env bash
"$PWD/bin/nbep" "\$@"
rc=\$?
[ "\$1" = run ] || exit \$rc
while [ \$# -gt 1 ] && [ "\$1" != --summary ]; do shift; done
sed -n 's/.*"spheres": \([0-9]*\).*"steps": \([0-9]*\).*/\2 \1/p' "\$2" >>"$tmp/ran.log"
exit \$rc
END
chmod +x "$tmp/nbep-logged"
NBEP=$tmp/nbep-logged SPHERES=64 STEPS=5 RUNS=1 THREADS_LIST=1 RANKS_LIST=1 \
    OUT="$tmp/group.csv" WORK="$tmp/work" timeout -k 5 120 bash scripts/slurm-scaling.sbatch \
    inputs/paper-box.deck --set 'run={algorithm="predictive";}' \
    --set 'spheres.[0]={count=3; radius=0.01; mass=1.0; place="random";}' >"$tmp/group.out" 2>&1
rc=$?
check "... and a user's --set of the run and spheres groups: exit 0 (got $rc), each run 5 steps of 64 spheres as the CSV says ($(tr '\n' ';' <"$tmp/ran.log"))" \
    "[ $rc = 0 ] && [ \$(wc -l <'$tmp/ran.log') = 2 ] && [ \"\$(sort -u '$tmp/ran.log')\" = '5 64' ] &&
     [ \$(cut -d, -f5,7 '$tmp/group.csv' | sort -u | grep -c '^64,5\$') = 1 ]"

exit $fail
