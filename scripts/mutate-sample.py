#!/usr/bin/env python3
"""A random sample of mechanical mutants of nbep's core, each run against every unit test: the
suite's kill rate on bugs nobody chose (scripts/mutate.py's list holds the bugs its authors
thought of, each aimed at the tests meant to catch it; a sample drawn at random says how much
the tests catch of what they were not aimed at).

A mutant is one operator changed at a site drawn at random (uniformly over the sites of the
files named) outside comments, strings, preprocessor lines and assertions: a comparison
(< <=, > >=, == !=), an arithmetic operator (+ -, * /), a logical one (&& ||), a negation
dropped (!x to x), or a floating literal other than 0 doubled. Each is built in a scratch copy of the tree
(make MPI=0 bin/nbep check-programs) and run against every C unit test program, the fastest
first, each under a time limit (a hang is a kill: one that passes the limit runs once more
under ten times it, so that a machine busy elsewhere does not pass for a hang), up to the
first that fails.

Usage: python3 scripts/mutate-sample.py [-n N] [--seed S] [--files src/a.c,...] [--timeout S]
       [--lines src/a.c:L,...] [--list] [--selftest]
(--lines: every site on those lines, no draw: a survivor or a doubtful kill run again.)
Prints one row per mutant (file:line, the change and its column, the verdict and the test that
killed it) and ends with "sample: K killed, S survived, B did not build of N". A survivor is
either a gap in the tests or an equivalent mutant (no observable change): each is for a person to
judge; docs/mutation-log.md keeps the judgements. Exit 0 always once the sample ran (a
survivor is a finding, not a failure of the script), 2 on bad arguments.
"""
import argparse
import os
import random
import re
import shutil
import sys
import tempfile
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from mutate import ROOT, copy_tree, run  # noqa: E402  (one copy of the tree, one runner)

# the physics kernels and every engine's way of finding pairs (README, Algorithms)
CORE = ["src/physics.c", "src/contact.c", "src/predict.c", "src/pred_react.c",
        "src/pred_find.c", "src/pred_cells.c", "src/pred_settle.c", "src/algo_predictive.c",
        "src/algo_detect.c", "src/evloop.c", "src/evloop_team.c", "src/calendar.c",
        "src/nblist.c", "src/cells.c", "src/periodic.c", "src/feq.c", "src/grid.c",
        "src/bvh.c", "src/sim.c"]

# operator -> its replacement; each a regular expression that matches the operator alone
# (not part of a longer one: "<" not in "<<", "<=" or "->")
SWAPS = [
    (r"(?<![<>=!-])<(?![<=])", "<="), (r"<=", "<"),
    (r"(?<![<>=-])>(?![>=])", ">="), (r">=", ">"),
    (r"==", "!="), (r"!=", "=="),
    (r"&&", "||"), (r"\|\|", "&&"),
    (r"(?<=[\w)\]] )\+(?= [\w(])", "-"), (r"(?<=[\w)\]] )-(?= [\w(])", "+"),
    (r"(?<=[\w)\]] )\*(?= [\w(])", "/"), (r"(?<=[\w)\]] )/(?= [\w(])", "*"),
    (r"!(?=[\w(])(?!=)", ""),
]
FLOAT = re.compile(r"(?<![\w.])(\d+\.\d*(?:e[+-]?\d+)?|\d+e[+-]?\d+)(?![\w.])")


def blank_ignored(text):
    """The text with comments, strings, character literals, preprocessor lines and lines
    holding an assertion or a prefetch (no effect on results by design) blanked, offsets
    kept."""
    out = list(text)

    def blank(a, b):
        for k in range(a, b):
            if out[k] != "\n":
                out[k] = " "

    for m in re.finditer(r'/\*.*?\*/|//[^\n]*|"(?:\\.|[^"\\\n])*"|\'(?:\\.|[^\'\\\n])*\'',
                         text, re.S):
        blank(m.start(), m.end())
    masked = "".join(out)
    pos = 0
    for line in masked.split("\n"):
        s = line.strip()
        if s.startswith("#") or "assert(" in s or "PREFETCH" in s or "_Static_assert" in s:
            blank(pos, pos + len(line))
        pos += len(line) + 1
    return "".join(out)


def sites(path):
    """Every (offset, length, replacement) of path's mutable operators."""
    with open(os.path.join(ROOT, path)) as f:
        text = f.read()
    return text, sorted(find_sites(blank_ignored(text)))


def find_sites(masked):
    """The (offset, length, replacement) of every mutable operator of masked text."""
    found = []
    for pat, repl in SWAPS:
        for m in re.finditer(pat, masked):
            found.append((m.start(), m.end() - m.start(), repl))
    for m in FLOAT.finditer(masked):
        if float(m.group(1)) == 0.0:  # doubling 0 changes nothing
            continue
        found.append((m.start(), m.end() - m.start(), "(2.0 * " + m.group(1) + ")"))
    return found


SELFTEST_C = r"""/* a < b in a comment, and a - b */
#define LESS(a, b) ((a) < (b))
static int f(int a, int b, const double *p, const struct s *q)
{
    assert(a < b);
    const char *s = "a < b", c = '<';
    if (a < b && !p) // a > b
        return a - b;
    return p[0] * 0.5 >= 0.0 ? a << 1 : q->k != 2;
}
"""
# the sites SELFTEST_C has, by the text each replaces: the comment, the macro, the assertion,
# the string and the character, the shift, the arrow, the pointer's star and the literal 0.0
# have none
SELFTEST_WANT = sorted(["<", "&&", "!", "-", "*", "0.5", ">=", "!="])


def selftest():
    """The site finder on SELFTEST_C: every site it should find, and none other."""
    masked = blank_ignored(SELFTEST_C)
    got = sorted(SELFTEST_C[off:off + ln] for off, ln, _ in find_sites(masked))
    print(f"selftest: sites {got}")
    if got != SELFTEST_WANT:
        print(f"selftest: FAIL: want {SELFTEST_WANT}", file=sys.stderr)
        return 1
    print("selftest: ok")
    return 0


def unit_tests(scratch):
    """The C unit test programs the build made."""
    d = os.path.join(scratch, "build", "tests")
    return sorted(f for f in os.listdir(d)
                  if f.startswith("test_") and not f.endswith(".d")
                  and os.access(os.path.join(d, f), os.X_OK))


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("-n", type=int, default=20, help="mutants to draw (default 20)")
    ap.add_argument("--seed", type=int, default=1, help="the draw's seed (default 1)")
    ap.add_argument("--files", default=",".join(CORE), help="comma-separated sources")
    ap.add_argument("--timeout", type=float, default=4.0,
                    help="a test's limit as a multiple of its time on the unmutated tree, "
                         "at least 20 s (default 4)")
    ap.add_argument("--jobs", type=int, default=2, help="make -j per build (default 2)")
    ap.add_argument("--lines", default="",
                    help="comma-separated FILE:LINE: every site on those lines instead of a "
                         "draw (to run a draw's survivors or doubtful kills again)")
    ap.add_argument("--list", action="store_true", help="print the draw and exit")
    ap.add_argument("--selftest", action="store_true",
                    help="check the site finder on a fixed snippet (make check) and exit")
    a = ap.parse_args()
    if a.selftest:
        return selftest()
    files = [f for f in a.files.split(",") if f]
    for f in files:
        if not os.path.isfile(os.path.join(ROOT, f)):
            print(f"mutate-sample: no such source: {f}", file=sys.stderr)
            return 2
    if a.n < 1:
        print("mutate-sample: -n must be at least 1", file=sys.stderr)
        return 2
    texts, pool = {}, []
    for f in files:
        texts[f], found = sites(f)
        pool += [(f,) + s for s in found]
    def describe(m):
        """Where (FILE:LINE, as --lines takes it) and the change, with its column: a line
        can hold several sites of one operator (bvh.c's widening has three '+')."""
        f, off, ln, repl = m
        text = texts[f]
        line = text.count("\n", 0, off) + 1
        col = off - (text.rfind("\n", 0, off) + 1) + 1
        return f"{f}:{line}", f"'{text[off:off + ln]}' -> '{repl}' at column {col}"

    if a.lines:
        want = [w for w in a.lines.split(",") if w]
        draw = [m for m in pool if describe(m)[0] in want]
        found = {describe(m)[0] for m in draw}
        for w in want:
            if w not in found:
                print(f"mutate-sample: no site at {w} (a core source's line, --files)",
                      file=sys.stderr)
                return 2
        print(f"mutate-sample: {len(pool)} sites in {len(files)} files, "
              f"{len(draw)} on {len(want)} lines", flush=True)
    else:
        rng = random.Random(a.seed)
        draw = rng.sample(pool, min(a.n, len(pool)))
        print(f"mutate-sample: {len(pool)} sites in {len(files)} files, seed {a.seed}, "
              f"{len(draw)} drawn", flush=True)
    if a.list:
        for m in draw:
            print("  %s  %s" % describe(m))
        return 0

    scratch = tempfile.mkdtemp(prefix="nbep-sample-")
    try:
        copy_tree(scratch)
        if run(["make", f"-j{a.jobs}", "MPI=0", "bin/nbep", "check-programs"], scratch) != 0:
            print("mutate-sample: the unmutated tree does not build", file=sys.stderr)
            return 1
        os.makedirs(os.path.join(scratch, "build", "tests", "tmp"), exist_ok=True)
        base = {}
        for t in unit_tests(scratch):
            t0 = time.monotonic()
            r = run(["timeout", "-k", "5", "600", os.path.join("build", "tests", t)], scratch)
            if r != 0:
                print(f"mutate-sample: {t} fails on the unmutated tree (exit {r})",
                      file=sys.stderr)
                return 1
            base[t] = time.monotonic() - t0
        order = sorted(base, key=base.get)
        print(f"mutate-sample: {len(order)} unit test programs pass, "
              f"{sum(base.values()):.0f} s in all", flush=True)
        counts = {"killed": 0, "survived": 0, "no build": 0}
        for m in draw:
            f, off, ln, repl = m
            where, change = describe(m)
            target = os.path.join(scratch, f)
            text = texts[f]
            with open(target, "w") as out:
                out.write(text[:off] + repl + text[off + ln:])
            t0 = time.monotonic()
            verdict, why = "survived", ""
            if run(["make", f"-j{a.jobs}", "MPI=0", "bin/nbep", "check-programs"], scratch) != 0:
                verdict = "no build"
            else:
                for t in order:
                    lim = max(20.0, a.timeout * base[t])
                    r = run(["timeout", "-k", "5", f"{lim:.0f}",
                             os.path.join("build", "tests", t)], scratch)
                    if r in (124, 137):
                        # a hang, or a machine busy with something else (spinning barriers
                        # on more threads than free cores slow down many times over): once
                        # more, under ten times the limit, before it counts as a hang
                        r = run(["timeout", "-k", "5", f"{10 * lim:.0f}",
                                 os.path.join("build", "tests", t)], scratch)
                    if r != 0:
                        verdict = "killed"
                        why = t + (" (hung)" if r in (124, 137) else f" (exit {r})")
                        break
            with open(target, "w") as out:
                out.write(text)
            counts[verdict] += 1
            print(f"{where:28} {change:46} {verdict:9} {why} "
                  f"({time.monotonic() - t0:.0f} s)", flush=True)
    finally:
        shutil.rmtree(scratch, ignore_errors=True)
    print(f"sample: {counts['killed']} killed, {counts['survived']} survived, "
          f"{counts['no build']} did not build of {len(draw)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
