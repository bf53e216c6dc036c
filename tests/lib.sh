# shellcheck shell=bash
# What the shell tests (tests/test_*.sh) share, sourced as each one's first command:
#     . "$(dirname "$0")/lib.sh"
# so that the way a test finds its files, names its scratch folder and counts its failures is
# written once. Not a test itself (make check runs tests/test_*.sh only); bash, as the tests
# are (the directive above tells shellcheck, which cannot see a shebang here).

# An unset variable is a mistake in the test, not an empty string. The tests run from the
# repository's root wherever they are started from (make check, scripts/mutate.py's scratch
# copy, by hand), so that bin/nbep, inputs/ and build/tests/tmp/ are the same paths in each.
set -u
cd "$(dirname "${BASH_SOURCE[0]}")/.."

# The Python the tests run: the system's, where scripts/install-deps.sh installs h5py, numpy and
# matplotlib, not whichever python3 comes first on PATH (a virtual environment's may lack them).
PY=/usr/bin/python3

# check NAME CONDITION: evaluates CONDITION (values put in when the line is made, or escaped to
# be read at the check) and prints "ok   NAME" or "FAIL NAME". A failure does not end the test:
# the checks after it still run and report, and test_end makes the exit status 1.
fail=0
check() { if eval "$2"; then echo "ok   $1"; else echo "FAIL $1"; fail=1; fi; }

# test_tmp NAME: $tmp is the test's scratch folder, build/tests/tmp/NAME, made afresh. Tests run
# side by side (scripts/run-tests.sh), so each keeps to a folder of its own; afresh, so that a
# file an earlier run left there cannot pass for one this run should have written.
test_tmp() {
    tmp=build/tests/tmp/$1
    rm -rf "$tmp" && mkdir -p "$tmp"
}

# need_py MODULE...: unless $PY imports every MODULE, says which are wanted in one line and
# ends the test with 77, which scripts/run-tests.sh counts as a skip, never a pass (until
# 2026-11-30 test_settle.sh and test_viz.sh ended with 0 there: a machine without h5py counted
# them as passed).
need_py() {
    local list
    list=$(IFS=,; echo "$*")
    "$PY" -c "import $list" 2>/dev/null && return
    list=${list//,/, }
    if [ $# = 1 ]; then
        echo "skipped: $PY with $1 not found (scripts/install-deps.sh installs it)"
    else
        echo "skipped: $PY with ${list%, *} and ${!#} not found (scripts/install-deps.sh installs them)"
    fi
    exit 77
}

# one_line: $tmp/stderr, where a test's nbep runs leave their errors (test_cli.sh's run_nbep,
# test_sweep_cli.sh's run_sweep and run_check) is one line (SPEC: "Every error is one line on
# stderr that says where and what").
one_line() { [ "$(wc -l <"$tmp/stderr")" -eq 1 ]; }

# bytes_of: the bytes of a size as nbep prints it ("1.82 MB", "682 kB": powers of 1000), read on
# stdin; nothing for anything else.
bytes_of() {
    awk 'NF == 2 && $1 ~ /^[0-9.]+$/ {
        m = $2 == "B" ? 1 : $2 == "kB" ? 1e3 : $2 == "MB" ? 1e6 : $2 == "GB" ? 1e9 : $2 == "TB" ? 1e12 : 0
        if (m) printf "%.17g\n", $1 * m }'
}

# sanitized: true under `make asan` (which sets NBEP_TEST_SAN), where some checks measure the
# sanitizer instead of nbep: peak RSS (AddressSanitizer's shadow memory and quarantine), a
# limit on the address space (it reserves terabytes of it), a library put first with
# LD_PRELOAD (it must come first itself). `sanitized NAME WHY` is true there, and prints
# "skip NAME (under SANITIZER: WHY)" for the check it stands in for.
sanitized() {
    [ -n "${NBEP_TEST_SAN:-}" ] || return 1
    echo "skip $1 (under $NBEP_TEST_SAN: $2)"
}

# under_gdb COMMAND...: COMMAND (a gdb that runs bin/nbep) with LeakSanitizer off, which cannot
# work under ptrace and would end the run with its own error (make asan; a plain build ignores
# ASAN_OPTIONS).
under_gdb() { ASAN_OPTIONS="${ASAN_OPTIONS:+$ASAN_OPTIONS:}detect_leaks=0" "$@"; }

# test_end NAME: the closing line "NAME: all passed" when no check failed, and the exit status,
# 1 when one did.
test_end() {
    [ $fail = 0 ] && echo "$1: all passed"
    exit $fail
}
