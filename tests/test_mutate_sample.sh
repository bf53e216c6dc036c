#!/usr/bin/env bash
# scripts/mutate-sample.py, the random sample of mechanical mutants of the core, without its
# long run: its site finder on a fixed C snippet (every operator it should mutate and none in
# a comment, a macro, an assertion, a string, a shift, an arrow or a pointer's declaration;
# the selftest), a draw that is the same for the same seed and names sites in the core's
# sources only (each line holding the text it changes at the column it names), --lines naming
# the sites of a line, and its one-line refusals of a bad source, count or line (exit 2).
# Run from anywhere; exit status 1 when a check fails.
. "$(dirname "$0")/lib.sh"
test_tmp mutate_sample
"$PY" scripts/mutate-sample.py --selftest >"$tmp/self.txt" 2>&1
rc=$?
check "mutate-sample.py --selftest: exit 0 (got $rc): $(tr '\n' ';' <"$tmp/self.txt" | head -c 400)" \
    "[ $rc = 0 ] && grep -q '^selftest: ok$' '$tmp/self.txt'"
"$PY" scripts/mutate-sample.py -n 25 --seed 3 --list >"$tmp/a.txt" 2>&1
"$PY" scripts/mutate-sample.py -n 25 --seed 3 --list >"$tmp/b.txt" 2>&1
"$PY" scripts/mutate-sample.py -n 25 --seed 4 --list >"$tmp/c.txt" 2>&1
check "one seed, one draw" "cmp -s '$tmp/a.txt' '$tmp/b.txt'"
check "another seed, another draw" "! cmp -s '$tmp/a.txt' '$tmp/c.txt'"
check "the draw lists 25 sites, each a core source's line and a change at a column" \
    "[ \$(grep -cE \"^  src/[a-z_]+\\.c:[0-9]+  '[^']+' -> '[^']*' at column [0-9]+\$\" '$tmp/a.txt') = 25 ]"
# each drawn site's line holds the text it changes, at the column named
bad=0
while read -r where change; do
    f=${where%%:*} line=${where##*:} from=${change#\'} from=${from%%\' ->*} col=${change##* }
    text=$(sed -n "${line}p" "$f")
    [ "${text:col-1:${#from}}" = "$from" ] || bad=$((bad + 1))
done < <(sed -n "s/^  \(src[^ ]*\)  \(.*\)$/\1 \2/p" "$tmp/a.txt")
check "every drawn site's line holds the text it changes at its column ($bad do not)" "[ $bad = 0 ]"
# --lines: every site on the lines named, no draw; a line without a site refused
first=$(sed -n "s/^  \(src[^ ]*\)  .*$/\1/p" "$tmp/a.txt" | head -1)
"$PY" scripts/mutate-sample.py --lines "$first" --list >"$tmp/l.txt" 2>&1
rc=$?
check "--lines $first: exit 0 (got $rc), its sites only, the drawn one among them" \
    "[ $rc = 0 ] && [ \$(grep -c '^  src' '$tmp/l.txt') -ge 1 ] &&
     [ \$(grep '^  src' '$tmp/l.txt' | grep -vc '^  $first  ') = 0 ] &&
     grep -qF \"\$(grep -m1 '^  $first  ' '$tmp/a.txt')\" '$tmp/l.txt'"
"$PY" scripts/mutate-sample.py --lines src/cells.c:1 --list >"$tmp/out" 2>"$tmp/err"
rc=$?
check "--lines at a comment (src/cells.c:1): exit 2 (got $rc), one line naming it" \
    "[ $rc = 2 ] && [ \$(wc -l <'$tmp/err') = 1 ] && grep -q 'src/cells.c:1' '$tmp/err'"
"$PY" scripts/mutate-sample.py --files src/nope.c --list >"$tmp/out" 2>"$tmp/err"
rc=$?
check "a source that does not exist: exit 2 (got $rc), one line naming it" \
    "[ $rc = 2 ] && [ \$(wc -l <'$tmp/err') = 1 ] && grep -q 'src/nope.c' '$tmp/err'"
"$PY" scripts/mutate-sample.py -n 0 --list >"$tmp/out" 2>"$tmp/err"
rc=$?
check "-n 0: exit 2 (got $rc), one line" "[ $rc = 2 ] && [ \$(wc -l <'$tmp/err') = 1 ]"
test_end mutate_sample
