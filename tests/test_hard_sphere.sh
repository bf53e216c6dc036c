#!/usr/bin/env bash
# scripts/hard-sphere.py (README, Checking a run: a hard-sphere fluid against theory). First on a
# file made here in nbep-1's layout whose answers are known exactly: two spheres flying
# straight through a periodic box's faces (the image counts unwrap them; the centre of mass
# drifts, and its flight is taken out), so the MSD of each lag is |v1 - v2|^2 lag^2 / 4, and
# /stats rows whose pressure and collision rate follow from their sums; the window (--from)
# takes the steps and frames after it. Then on a real run of inputs/hard-sphere-fluid.deck
# with 500 spheres over 20 time units: pressure and collision rate within 2 % of
# Carnahan-Starling and Enskog after the melt, D above Enskog's D_E (the fluid at phi = 0.30,
# measured 1.36 D_E here and 1.27 with 32000 spheres), and the figures of the whole run equal
# the summary's pressure. Last, errors: one line, exit 2.
# Run from anywhere; exit status 1 when a check fails.
. "$(dirname "$0")/lib.sh"
test_tmp hard_sphere
need_py h5py numpy
[ -x bin/nbep ] || { echo "FAIL bin/nbep not built"; exit 1; }
HS=scripts/hard-sphere.py

# ---- a file whose answers are known ---------------------------------------------------------
"$PY" - "$tmp/made.h5" <<'PYEOF'
import sys, h5py, numpy as np
L = np.array([4.0, 5.0, 6.0]); dt = 0.25; every = 4; steps = 40  # frames at t = 0, 1, ..., 10
v = np.array([[1.7, -0.9, 2.3], [-0.4, 1.1, 0.6]]); p0 = np.array([[1.0, 2.0, 3.0], [3.0, 1.0, 5.0]])
with h5py.File(sys.argv[1], "w") as f:
    f.attrs["format"] = "nbep-1"; f.attrs["periodic"] = np.array([1, 1, 1], np.int32)
    f.attrs["box_min"] = np.zeros(3); f.attrs["box_max"] = L
    f.attrs["restitution"] = 1.0; f.attrs["dt"] = dt
    f["spheres/radius"] = np.array([0.5, 0.5]); f["spheres/mass"] = np.array([2.0, 2.0])
    f["spheres/acceleration"] = np.zeros((2, 3))
    t = np.arange(0, steps + 1, every) * dt
    u = p0[None] + t[:, None, None] * v[None]                    # unwrapped
    img = np.floor(u / L).astype(np.int32)
    f["frames/time"] = t; f["frames/step"] = np.arange(0, steps + 1, every)
    f["frames/position"] = u - img * L; f["frames/image"] = img
    f["frames/velocity"] = np.broadcast_to(v, u.shape).copy()
    f["frames"].attrs["count"] = np.uint64(len(t))
    s = np.arange(1, steps + 1)
    f["stats/step"] = s
    f["stats/kinetic_energy"] = np.where(s <= 8, 3.0, 6.0)   # kT = 2 KE / 3N: 1, then 2
    f["stats/virial"] = np.where(s <= 8, 0.0, 0.3)
    f["stats/collisions"] = np.where(s % 2 == 0, 1, 0).astype(np.uint64)
    f["stats"].attrs["count"] = np.uint64(steps)
PYEOF
"$PY" $HS "$tmp/made.h5" --from 2 --json >"$tmp/made.json" 2>"$tmp/err.txt"
rc=$?
check "a made file: exit 0 (got $rc), nothing on stderr" "[ $rc = 0 ] && [ ! -s '$tmp/err.txt' ]"
"$PY" - "$tmp/made.json" >"$tmp/made.txt" <<'PYEOF'
import json, math, sys
r = json.load(open(sys.argv[1]))
v = [[1.7, -0.9, 2.3], [-0.4, 1.1, 0.6]]
rel = sum((a - b) ** 2 for a, b in zip(*v)) / 4    # each sphere's speed about the centre of mass
sigma, m, N, V = 1.0, 2.0, 2, 120.0
kT = 2.0                                            # the window, t = 2 .. 10: KE 6 in every step
T, W, coll = 8.0, 0.3 * 32, 16                     # 32 steps of 0.25, one collision in two
tau = sigma * math.sqrt(m / kT)
eta = N * math.pi / 6 / V
want = {
    "steps": 32, "t_start": 2.0, "t_end": 10.0, "kT": kT, "tau": tau, "collisions": coll,
    "pressure": (N * kT + W / (3 * T)) / V,
    "beta_p_sigma3": (N * kT + W / (3 * T)) / V / kT,
    "collision_rate": 2 * coll / (N * T) * tau,
    "carnahan_starling": N / V * (1 + eta + eta**2 - eta**3) / (1 - eta) ** 3,
    "frames": 9, "lag": 1.0, "fit_lags": [2.0, 4.0],
    # least squares of rel lag^2 over lags 2 .. 4 (of 8: a fifth to a half): slope rel (2 + 4),
    # over 6, in sigma^2/tau
    "diffusion": rel * 6 / 6 * tau,
}
bad = [k for k, w in want.items()
       if not (r[k] == w if isinstance(w, (int, list)) else math.isclose(r[k], w, rel_tol=1e-12))]
msd_bad = [j for j, x in enumerate(r["msd"]) if not math.isclose(x, rel * (j + 1) ** 2, rel_tol=1e-12)]
if r["diffusion_err"] is not None:  # 2 spheres: no 8 groups to scatter
    bad.append("diffusion_err")
print("ok" if not bad and not msd_bad and len(r["msd"]) == 8 else f"bad {bad} msd {msd_bad} {r}")
PYEOF
check "its pressure, rate, kT, window and unwrapped MSD (lag^2 |v1 - v2|^2 / 4) as worked by hand" \
    "[ \"\$(cat '$tmp/made.txt')\" = ok ] || { cat '$tmp/made.txt'; false; }"

# ---- a real fluid ---------------------------------------------------------------------------
L=9.556138980221721 # (500 pi / (6 * 0.30))^(1/3)
bin/nbep run inputs/hard-sphere-fluid.deck --quiet -o "$tmp/fluid.h5" --summary "$tmp/fluid.json" \
    --set 'spheres.[0].count=500' --set "box.max=[$L,$L,$L]" -n 200 2>"$tmp/err.txt"
check "a 500-sphere fluid at phi = 0.30 runs 20 time units" "[ \$? = 0 ] && [ -s '$tmp/fluid.h5' ]"
"$PY" $HS "$tmp/fluid.h5" --from 2 >"$tmp/fluid.txt" 2>"$tmp/err.txt"
rc=$?
check "hard-sphere.py on it: exit 0 (got $rc), its four lines" \
    "[ $rc = 0 ] && grep -q '^pressure: ' '$tmp/fluid.txt' && grep -q '^collisions: ' '$tmp/fluid.txt' &&
     grep -q '^diffusion:  D = ' '$tmp/fluid.txt' && grep -q '^window:     t = 2 .. 20 (180 steps of 0.1)' '$tmp/fluid.txt'"
check "... and nothing on stderr (a window past the start, 180 frames)" "[ ! -s '$tmp/err.txt' ]"
"$PY" $HS "$tmp/fluid.h5" --from 2 --json >"$tmp/fluid-w.json"
"$PY" $HS "$tmp/fluid.h5" --json >"$tmp/fluid-all.json" 2>"$tmp/err.txt"
check "a window from t = 0: a note on stderr that the start is in it, the JSON alone on stdout" \
    "grep -q '^hard-sphere.py: note: the window starts at t = 0' '$tmp/err.txt' && [ \$(wc -l <'$tmp/err.txt') = 1 ]"
"$PY" $HS "$tmp/fluid.h5" --from 16 >/dev/null 2>"$tmp/err.txt"
check "a window of 5 frames: a note that D is rough" \
    "grep -q '^hard-sphere.py: note: only 5 frames in the window: D is a rough figure' '$tmp/err.txt'"
"$PY" - "$tmp/fluid-w.json" "$tmp/fluid-all.json" "$tmp/fluid.json" >"$tmp/fluid-check.txt" <<'PYEOF'
import json, sys
w, a, s = (json.load(open(p)) for p in sys.argv[1:4])
ok = (abs(w["beta_p_sigma3"] / w["carnahan_starling"] - 1) < 0.02 and
      abs(w["collision_rate"] / w["enskog_rate"] - 1) < 0.02 and
      1.0 < w["diffusion"] / w["enskog_diffusion"] < 1.6 and
      0 < w["diffusion_err"] < 0.1 * w["diffusion"] and w["fit_lags"] == [4.0, 9.0] and
      abs(a["pressure"] / s["pressure"] - 1) < 1e-12 and
      a["collisions"] == s["sphere_collisions"])
print("ok" if ok else f"bad: window {w} whole {a} summary {s}")
PYEOF
check "pressure and rate within 2 % of theory after t = 2, D/D_E in (1, 1.6) fitted over lags 4 .. 9 (of 18) with an error under 10 %, the whole run's pressure the summary's" \
    "[ \"\$(cat '$tmp/fluid-check.txt')\" = ok ] || { head -c 600 '$tmp/fluid-check.txt'; false; }"

# ---- errors: one line, exit 2 ---------------------------------------------------------------
bin/nbep run inputs/two-spheres.deck --quiet -o "$tmp/closed.h5" -n 10
# spheres at rest: no temperature (until 2026-12-05 a ZeroDivisionError's traceback)
cp "$tmp/made.h5" "$tmp/rest.h5"
"$PY" -c "import h5py, sys; f = h5py.File(sys.argv[1], 'r+'); f['stats/kinetic_energy'][:] = 0.0" "$tmp/rest.h5"
for c in "$tmp/closed.h5:not a fully periodic box" "$tmp/none.h5:no such file" \
         "$tmp/rest.h5:mean kinetic energy from t = 0 is 0: no temperature to reduce the pressure and rates by" \
         "$tmp/fluid.h5 --from 30:no step of the run starts at t = 30 or later" \
         "$tmp/fluid.h5 --from -1:--from must be a time >= 0"; do
    args=${c%%:*} want=${c#*:}
    # shellcheck disable=SC2086
    "$PY" $HS $args >"$tmp/out.txt" 2>"$tmp/err.txt"
    rc=$?
    check "hard-sphere.py $args: exit 2 (got $rc), one line: $want" \
        "[ $rc = 2 ] && [ \$(wc -l <'$tmp/err.txt') = 1 ] && grep -q -- '$want' '$tmp/err.txt' && [ ! -s '$tmp/out.txt' ]"
done

test_end hard_sphere
