#!/usr/bin/python3
"""A hard-sphere fluid run against theory: pressure, collision rate and self-diffusion.

    scripts/hard-sphere.py RUN.h5 [--from T0] [--json]

RUN.h5 is an nbep run of elastic spheres of one radius and one mass, nothing accelerating, in a
fully periodic box (inputs/hard-sphere-fluid.deck and its kind). Over the window from time T0
(default 0; a lattice start has melted by about one time unit, so --from 2 leaves the start
out) to the run's last complete step or frame, it prints, in units of the diameter sigma, the
mass m and kT = 2 <KE> / (3 N) (the window's mean over the steps' ends), with the time unit
tau = sigma sqrt(m / kT):

  pressure     beta P sigma^3 = (N kT + W / (3 T)) sigma^3 / (V kT), from /stats/virial (W, its
               sum) and /stats/kinetic_energy over the window's steps (the summary's pressure
               is P over the whole run), beside Carnahan-Starling's equation of state,
               rho sigma^3 (1 + eta + eta^2 - eta^3) / (1 - eta)^3 (eta the packing fraction),
               and past freezing (eta = 0.494) Speedy's for the FCC crystal, the one compared
               with past melting (0.545: inputs/hard-sphere-crystal.deck);
  collisions   2 collisions / (N T) per sphere per tau, from /stats/collisions, beside
               Enskog's rate 4 rho sigma^2 g sqrt(pi kT / m), g = (1 - eta/2) / (1 - eta)^3
               (Carnahan-Starling's contact value);
  diffusion    D from the mean-squared displacement of the unwrapped centres (SPEC:
               position + image * (box_max - box_min)) less the centre of mass's (a start
               with speeds in random directions has a total momentum, and its drift would
               add a t^2 term), averaged over the frames as time origins: the least-squares
               slope of MSD against the lag over the lags from a fifth to a half of the
               longest, divided by 6 (the longer lags have fewer time origins: the worst
               sampled), with its standard error from 8 groups of the spheres, each fitted
               alone (at least 16 spheres);
               beside Enskog's D_E = 3 / (8 rho sigma^2 g)
               sqrt(kT / (pi m)). The MSD must grow linearly at long lags: the table of MSD / (6
               lag) beside it levels off where it does. (A fluid's D lies above D_E at
               moderate density: collisions are not uncorrelated there, as Alder, Gass and
               Wainwright found in 1970.)

The window's steps count in the pressure and the rate (a step from t - dt to t is in it when
t - dt >= T0), its frames in the diffusion (frames at T0 or later, evenly spaced; a last frame
off their grid, the end of a run whose steps are not a multiple of output.every, is left
out). --json prints the same figures as one JSON object. Without /stats (output.stats =
false) the pressure and rate are skipped, without positions in the frames the diffusion.
An error (a missing file, a scene this does not describe, a window without steps) is one line
on stderr and exit status 2.

Needs h5py and numpy (Debian: python3-h5py python3-numpy)."""
import argparse
import json
import math
import os
import sys

try:
    import h5py
    import numpy as np
except ImportError as err:  # one line, as every other error here, not a traceback
    print(f"hard-sphere.py: {err.name or err} is missing for {sys.executable}: install "
          "python3-h5py and python3-numpy (Debian), or run /usr/bin/python3", file=sys.stderr)
    sys.exit(2)


def fail(msg):
    print(f"hard-sphere.py: {msg}", file=sys.stderr)
    sys.exit(2)


def one_value(a, what, path):
    """The one value of array a (all equal), else an error naming what varies."""
    a = np.asarray(a)
    if a.size == 0:
        fail(f"{path}: no spheres")
    if not np.all(a == a.flat[0]):
        fail(f"{path}: the spheres' {what} differ ({a.min():g} to {a.max():g}): the theory "
             "here is for spheres of one size and mass")
    return float(a.flat[0])


def carnahan_starling(eta, rho_s3):
    """beta P sigma^3 of the hard-sphere fluid (Carnahan and Starling, 1969)."""
    return rho_s3 * (1 + eta + eta**2 - eta**3) / (1 - eta) ** 3


def speedy(eta):
    """beta P sigma^3 of the hard-sphere FCC crystal (Speedy, J. Phys.: Condens. Matter 10,
    4387 (1998)): beta P / rho = 3 / (1 - z) - a (z - b) / (z - c), z = rho sigma^3 / sqrt 2."""
    rho_s3 = 6 * eta / math.pi
    z = rho_s3 / math.sqrt(2)
    return rho_s3 * (3 / (1 - z) - 0.5921 * (z - 0.7072) / (z - 0.601))


# The fluid freezes at eta = 0.494 and the crystal melts at 0.545 (Hoover and Ree, 1968).
FREEZING, MELTING = 0.494, 0.545


def contact_value(eta):
    """g(sigma) of Carnahan-Starling's equation of state."""
    return (1 - eta / 2) / (1 - eta) ** 3


def msd_by_lag(u):
    """MSD for lags 1 .. F-1 frames of unwrapped centres u (F, N, 3), every frame an origin."""
    F = u.shape[0]
    out = np.zeros(F - 1)
    for j in range(1, F):
        d = u[j:] - u[:-j]
        out[j - 1] = np.mean(np.sum(d * d, axis=2))
    return out


def fit_range(n):
    """The lags' indices fitted, [first, last): a fifth to a half of the n lags, at least two
    (the longer lags, with fewer time origins, are the worst sampled: a fit over the longer
    half put D 1.3 % above one over 2 .. 30 tau on a 100-tau run, a physicist's review)."""
    first, last = n // 5, n // 2
    if last - first < 2:  # (n >= 2)
        last = min(n, first + 2)
        first = last - 2
    return first, last


def slope(x, y):
    """Least-squares slope of y against x."""
    x = np.asarray(x, float)
    y = np.asarray(y, float)
    xm, ym = x.mean(), y.mean()
    return float(np.sum((x - xm) * (y - ym)) / np.sum((x - xm) ** 2))


def analyse(path, t0):
    if not os.path.isfile(path):
        fail(f"{path}: no such file")
    try:
        f = h5py.File(path, "r")
    except (OSError, ValueError) as err:
        fail(f"{path}: cannot open it as HDF5 ({err})")
    with f:
        a = f.attrs
        fmt = a.get("format", b"")
        fmt = fmt.decode() if isinstance(fmt, bytes) else str(fmt)
        if fmt != "nbep-1":
            fail(f"{path}: not an nbep run file (format {fmt!r})")
        per = a.get("periodic")
        if per is None or "box_min" not in a or not all(int(p) for p in per):
            fail(f"{path}: not a fully periodic box (box.periodic = [true, true, true]): "
                 "the pressure and the theory here are a bulk fluid's")
        lo = np.asarray(a["box_min"], float)
        hi = np.asarray(a["box_max"], float)
        side = hi - lo
        V = float(np.prod(side))
        e = float(a.get("restitution", 1.0))
        if e != 1.0:
            fail(f"{path}: restitution {e:g}: the theory here is an elastic fluid's (e = 1)")
        acc = f["spheres/acceleration"][:]
        if np.any(acc != 0.0):
            fail(f"{path}: some spheres accelerate (gravity): the theory here is a free fluid's")
        r = one_value(f["spheres/radius"][:], "radii", path)
        m = one_value(f["spheres/mass"][:], "masses", path)
        N = int(f["spheres/radius"].shape[0])
        dt = float(a["dt"])
        sigma = 2 * r
        eta = N * math.pi * sigma**3 / 6 / V
        rho_s3 = N * sigma**3 / V
        g = contact_value(eta)
        res = {"file": path, "spheres": N, "packing_fraction": eta, "sigma": sigma, "mass": m,
               "box": side.tolist(), "from": t0, "dt": dt}

        have_stats = "stats" in f and "stats/virial" in f
        kT = None
        if have_stats:
            rows = int(f["stats"].attrs.get("count", f["stats/step"].shape[0]))
            step = f["stats/step"][:rows]
            keep = (step - 1) * dt >= t0 * (1 - 1e-12) - 1e-12 * dt
            n = int(np.count_nonzero(keep))
            if n == 0:
                fail(f"{path}: no step of the run starts at t = {t0:g} or later (its last "
                     f"ends at {rows * dt:g})")
            ke = f["stats/kinetic_energy"][:rows][keep]
            W = float(np.sum(f["stats/virial"][:rows][keep]))
            coll = int(np.sum(f["stats/collisions"][:rows][keep]))
            T = n * dt
            kT = 2 * float(np.mean(ke)) / (3 * N)
            # spheres at rest (or a file whose energies are not numbers) have no temperature,
            # and every reduced figure divides by it (until 2026-12-05 a ZeroDivisionError)
            if not kT > 0 or not math.isfinite(kT):
                fail(f"{path}: the spheres' mean kinetic energy from t = {t0:g} is {kT:g}: no "
                     f"temperature to reduce the pressure and rates by (a fluid at rest, or "
                     f"spheres given no speed)")
            tau = sigma * math.sqrt(m / kT)
            P = (N * kT + W / (3 * T)) / V
            res.update({"steps": n, "t_start": float((step[keep][0] - 1) * dt),
                        "t_end": float(step[keep][-1] * dt), "kT": kT,
                        "tau": tau, "pressure": P,
                        "beta_p_sigma3": P * sigma**3 / kT,
                        "carnahan_starling": carnahan_starling(eta, rho_s3),
                        "speedy_crystal": speedy(eta) if eta >= FREEZING else None,
                        "collisions": coll,
                        "collision_rate": 2 * coll / (N * T) * tau,
                        "enskog_rate": 4 * rho_s3 * g * math.sqrt(math.pi)})
        else:
            res["stats"] = None

        have_pos = "frames/position" in f
        if have_pos:
            count = int(f["frames"].attrs.get("count", f["frames/step"].shape[0]))
            ftime = f["frames/time"][:count]
            idx = [k for k in range(count) if ftime[k] >= t0 - 1e-12 * max(1.0, abs(t0))]
            if len(idx) >= 2:
                gaps = np.diff(ftime[idx])
                if len(idx) >= 3 and not math.isclose(gaps[-1], gaps[0], rel_tol=1e-9):
                    idx = idx[:-1]  # the last frame off the grid of output.every
                    gaps = gaps[:-1]
            if len(idx) < 2 or not np.allclose(gaps, gaps[0], rtol=1e-9):
                res["diffusion"] = None
                res["diffusion_why"] = (f"{len(idx)} frame(s) from t = {t0:g}" if len(idx) < 2
                                        else "frames not evenly spaced")
            else:
                pos = f["frames/position"][idx[0]:idx[-1] + 1]
                img = f["frames/image"][idx[0]:idx[-1] + 1]
                u = pos + img * side
                # less the centre of mass's own flight: speeds in random directions leave the
                # spheres a total momentum of about sqrt(N) m v, which moves them all
                # ballistically, t^2 in the MSD (N = 500: up to a third of D over 20 tau)
                u = u - u.mean(axis=1, keepdims=True)
                lag_step = float(gaps[0])
                msd = msd_by_lag(u)
                lags = lag_step * np.arange(1, len(msd) + 1)
                first, last = fit_range(len(msd))
                D_err = None
                if len(msd) >= 2:
                    D = slope(lags[first:last], msd[first:last]) / 6
                    if u.shape[1] >= 16:  # the spheres in 8 groups, each its own D
                        Ds = [slope(lags[first:last], msd_by_lag(g)[first:last]) / 6
                              for g in np.array_split(u, 8, axis=1)]
                        D_err = float(np.std(Ds, ddof=1) / math.sqrt(len(Ds)))
                else:
                    first, last = 0, 1
                    D = float(msd[0] / (6 * lags[0]))
                if kT is None:  # no stats: the temperature of the frames' velocities
                    if "frames/velocity" not in f:
                        fail(f"{path}: neither /stats nor velocities: no temperature")
                    v = f["frames/velocity"][idx[0]:idx[-1] + 1]
                    kT = m * float(np.mean(np.sum(v * v, axis=2))) / 3
                    res["kT"] = kT
                    res["tau"] = sigma * math.sqrt(m / kT)
                tau = res["tau"]
                res.update({"frames": len(idx), "lag": lag_step,
                            "msd": msd.tolist(), "lags": lags.tolist(),
                            "fit_lags": [float(lags[first]), float(lags[last - 1])],
                            "diffusion": D * tau / sigma**2,
                            "diffusion_err": (None if D_err is None
                                              else D_err * tau / sigma**2),
                            "enskog_diffusion": 3 / (8 * rho_s3 * g) / math.sqrt(math.pi)})
        else:
            res["diffusion"] = None
            res["diffusion_why"] = "no positions in the frames (output.fields)"
    return res


def report(res):
    side = " x ".join(f"{s:.6g}" for s in res["box"])
    print(f"run:        {res['file']}: N = {res['spheres']}, phi = {res['packing_fraction']:.4f}, "
          f"sigma = {res['sigma']:g}, m = {res['mass']:g}, periodic box {side}")
    if "steps" in res:
        print(f"window:     t = {res['t_start']:g} .. {res['t_end']:g} ({res['steps']} steps of "
              f"{res['dt']:g}); kT = {res['kT']:.6g} (2 <KE> / 3N), tau = "
              f"sigma sqrt(m / kT) = {res['tau']:.6g}")
        bp, cs, sp = res["beta_p_sigma3"], res["carnahan_starling"], res["speedy_crystal"]
        eta = res["packing_fraction"]
        if eta < MELTING:
            both = f"; Speedy (crystal) {sp:.4f}" if sp is not None else ""
            print(f"pressure:   beta P sigma^3 = {bp:.4f}   Carnahan-Starling {cs:.4f}   "
                  f"ratio {bp / cs:.4f}{both}")
        else:  # past melting: the FCC crystal's equation of state
            print(f"pressure:   beta P sigma^3 = {bp:.4f}   Speedy (FCC crystal) {sp:.4f}   "
                  f"ratio {bp / sp:.4f}; Carnahan-Starling (the fluid's) {cs:.4f}")
        if eta >= FREEZING:
            print(f"            (phi past freezing, {FREEZING}: a crystal or a metastable fluid; "
                  "the Enskog figures below are a fluid's)")
        cr, en = res["collision_rate"], res["enskog_rate"]
        print(f"collisions: {cr:.4f} per sphere per tau ({res['collisions']} in all)   "
              f"Enskog {en:.4f}   ratio {cr / en:.4f}")
    else:
        print("pressure:   - (no /stats: output.stats = false)")
        print("collisions: - (no /stats)")
    if res.get("diffusion") is None:
        print(f"diffusion:  - ({res['diffusion_why']})")
        return
    D, DE = res["diffusion"], res["enskog_diffusion"]
    err = f" +- {res['diffusion_err']:.4f}" if res.get("diffusion_err") is not None else ""
    print(f"diffusion:  D = {D:.4f}{err} sigma^2 / tau (MSD slope / 6 over lags "
          f"{res['fit_lags'][0]:g} .. {res['fit_lags'][1]:g}; {res['frames']} frames)   "
          f"Enskog {DE:.4f}   ratio {D / DE:.4f}")
    print("  lag   MSD / sigma^2   MSD / (6 lag) in sigma^2 / tau")
    s2, tau = res["sigma"] ** 2, res["tau"]
    for lag, msd in zip(res["lags"], res["msd"]):
        print(f"  {lag:<5g} {msd / s2:<15.4f} {msd / s2 / (6 * lag / tau):.4f}")


def main():
    ap = argparse.ArgumentParser(
        prog="hard-sphere.py", description=__doc__.split("\n\n")[0],
        epilog="README: Checking a run, a hard-sphere fluid against theory.")
    ap.add_argument("run", metavar="RUN.h5")
    ap.add_argument("--from", dest="t0", type=float, default=0.0, metavar="T0",
                    help="the window's start time (default 0)")
    ap.add_argument("--json", action="store_true", help="one JSON object on stdout")
    if any(a in ("-h", "--help") for a in sys.argv[1:]):
        print(__doc__)
        return
    args = ap.parse_args()
    if not (math.isfinite(args.t0) and args.t0 >= 0):
        fail(f"--from must be a time >= 0 (got {args.t0:g})")
    res = analyse(args.run, args.t0)
    # on stderr, so that --json stays one object: a window from the start takes in its
    # transient (a lattice melting: a new user read D/D_E = 0.90 off a 5-step run, 2026-12-01)
    if args.t0 == 0:
        print("hard-sphere.py: note: the window starts at t = 0, with the run's start in it (a "
              "lattice melting, say): pass --from T0 past it for the fluid's own figures",
              file=sys.stderr)
    if res.get("diffusion") is not None and res["frames"] < 6:
        print(f"hard-sphere.py: note: only {res['frames']} frames in the window: D is a rough "
              "figure (more frames: a longer run, or a smaller output.every)", file=sys.stderr)
    if args.json:
        print(json.dumps(res))
    else:
        report(res)


if __name__ == "__main__":
    try:
        main()
    except BrokenPipeError:  # a reader that stopped early (| head): not an error of ours
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        sys.exit(0)
