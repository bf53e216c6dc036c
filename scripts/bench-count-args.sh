# Sourced by scripts/bench-granular.sh and scripts/bench-hopper.sh, one check for both: called
# with the script's path and its arguments, `--help` prints the script's opening comment (its
# lines 2 up to `set -eu`) and exits 0, and anything but up to three positive integers (COUNT
# STEPS REPEATS) is refused with one line and exit 2, before any run (until 2026-11-30 `--help`
# went to nbep as COUNT, which refused it as a deck error after the table's set-up).
bench_count_args() {
    _me=$1
    _name=$(basename "$_me")
    shift
    case "${1:-}" in
      -h|--help) sed -n '2,/^set -eu/p' "$_me" | sed '$d; s/^# \{0,1\}//'; exit 0 ;;
    esac
    if [ $# -gt 3 ]; then
      echo "$_name: at most COUNT STEPS REPEATS (got $# arguments); --help" >&2
      exit 2
    fi
    for _a in "$@"; do
      case $_a in
        ''|*[!0-9]*|0|00*) echo "$_name: COUNT, STEPS and REPEATS are positive integers (got '$_a'); --help" >&2
                           exit 2 ;;
      esac
    done
}
