#!/usr/bin/env bash
# Every example deck in inputs/ is valid (nbep check) and runs to exit 0, scaled down to a few
# seconds: fewer steps, and fewer spheres for the big ones (--set as a user would). Beyond the
# exit status, each run's summary must hold what the deck's opening comment promises: energy
# kept to round-off for the elastic decks, energy lost for the dissipative ones, and contacts
# placed exactly (predictive: overlap at round-off of the radius).
. "$(dirname "$0")/lib.sh"
test_tmp decks
# summary field of a JSON summary file (flat object of numbers and strings)
field() { sed -n "s/.*\"$2\": \([^,}]*\).*/\1/p" "$1"; }
# awk comparisons on numbers written by the summary
holds() { awk -v x="$1" "BEGIN { exit !($2) }"; }

decks=(inputs/*.deck)
check "inputs/ holds the pile and hopper decks" \
    "[ -f inputs/pile.deck ] && [ -f inputs/hopper.deck ]"
for deck in "${decks[@]}"; do
    name=$(basename "$deck" .deck)
    bin/nbep check "$deck" >"$tmp/$name.check" 2>&1
    check "$name: nbep check accepts it" "[ $? -eq 0 ]"
    case "$name" in
        pile) args=(-n 300 --set spheres.[0].count=300) ;;   # the pour reaches the floor
        hopper) args=(-n 500) ;;                             # spheres land in the groove
        paper-box) args=(-n 50 --set spheres.[0].count=512) ;;
        sweep-restitution) args=(-n 50) ;;
        hard-sphere-fluid) args=(-n 20) ;;                  # 2 tau: about 3e5 collisions
        hard-sphere-crystal) args=(-n 20) ;;                # 1 tau: about 1e5 collisions
        bounce) args=(-n 1500) ;;                            # past the first bounce
        *) args=(-n 500) ;;
    esac
    bin/nbep run "$deck" --quiet -t 2 "${args[@]}" -o "$tmp/$name.h5" \
        --summary "$tmp/$name.json" 2>"$tmp/$name.err"
    rc=$?
    check "$name: runs to exit 0 (${args[*]})" "[ $rc -eq 0 ] && [ ! -s '$tmp/$name.err' ]"
    [ $rc -eq 0 ] || continue
    drift=$(field "$tmp/$name.json" energy_rel_drift)
    ovl=$(field "$tmp/$name.json" max_overlap_rel)
    e=$(sed -n 's/.*restitution = \([0-9.]*\);.*/\1/p' "$deck" | head -n 1)
    e=${e:-1.0}   # physics.restitution's default
    if holds "$e" "x == 1.0"; then
        # elastic: energy kept to the round-off of summing it over the run (1e-9 is far above)
        check "$name: e = 1 keeps energy (drift $drift)" "holds '$drift' 'x < 1e-9 && x > -1e-9'"
    else
        check "$name: e = $e loses energy (drift $drift)" "holds '$drift' 'x < 0'"
    fi
    # contacts placed by prediction: overlaps at round-off of the radius (1e-9 is far above)
    check "$name: no overlap beyond round-off ($ovl)" "holds '$ovl' 'x < 1e-9'"
    if [ "$name" = hard-sphere-crystal ]; then
        # the crystal's pressure after one tau, from the lattice: Speedy's 17.79 at phi = 0.60,
        # within 2 % (0.998 of it over 3 tau at this N; tests/test_periodic.c checks it closely)
        p=$(field "$tmp/$name.json" pressure)
        check "$name: the crystal's pressure is Speedy's ($p against 17.79)" \
            "holds '$p' 'x > 17.43 && x < 18.15'"
    fi
done
exit $fail
