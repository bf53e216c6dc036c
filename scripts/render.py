#!/usr/bin/python3
"""Draws frames of an nbep run (an nbep-1 HDF5 file) to PNG images.

    scripts/render.py RUN.h5 [--frames 0,10,-1] [--out DIR] [--view 3d|xy|xz|yz]
                             [--size 6] [--dpi 150] [--color speed|height|none]

Each frame becomes DIR/RUN-step-000120.png with --view 3d and DIR/RUN-step-000120-xz.png
(-xy, -xz or -yz: the view) for a projection, 000120 being the frame's step, with -height or
-none after it for those colourings (RUN-step-000120-xz-height.png); DIR defaults to the run
file's folder. Frames are indices into /frames (negative ones count from the last
complete frame: -1 is the last); only complete frames are used (the `count` attribute of
/frames), so a run still being written or killed can be drawn. --view 3d draws a perspective
scatter whose marker sizes follow the radii approximately; xy, xz and yz draw an orthographic
projection with every sphere a disc of its true radius (nearest drawn last). Spheres are
coloured by speed when the run wrote velocities (--color height colours by the coordinate
along the hidden or vertical axis). The box, from the file's box_min and box_max (a periodic
one too), or where an older file's planes form one, is drawn as an outline; in a projection,
each plane seen edge-on (its normal across the view: the hopper's groove in --view xz) is
drawn as a line. An error (a missing or unreadable file, a frame out of range) is one line on stderr
and exit status 2.

Needs h5py and matplotlib (Debian: python3-h5py python3-matplotlib)."""
import argparse
import errno
import math
import os
import sys

try:
    import h5py
    import numpy as np

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt  # noqa: E402
    from matplotlib.collections import EllipseCollection  # noqa: E402
except ImportError as err:  # one line, as every other error here, not a traceback
    print(f"render.py: {err.name or err} is missing for {sys.executable}: install "
          "python3-h5py and python3-matplotlib (Debian), or run /usr/bin/python3",
          file=sys.stderr)
    sys.exit(2)

AXES = {"x": 0, "y": 1, "z": 2}


def fail(message):
    """One line on stderr, exit 2 (bad input, as nbep's own)."""
    print("render.py: " + message, file=sys.stderr)
    sys.exit(2)


def parse_frames(text, count):
    """'0,10,-1' -> sorted distinct indices into the count complete frames."""
    out = []
    for item in text.split(","):
        item = item.strip()
        if not item:
            continue
        try:
            k = int(item)
        except ValueError:
            fail("--frames wants frame indices such as 0,10,-1 (-1: the last); got %r" % item)
        if k < 0:
            k += count
        if not 0 <= k < count:
            fail("frame %s is outside the %d complete frames" % (item, count))
        out.append(k)
    return sorted(set(out))


def box_of(f, pos, radius):
    """(lo, hi) of the run's box: its root attributes box_min and box_max (files since
    2026-11-27; a periodic box has no walls to tell it), or six axis-aligned planes that bound
    it; else of the spheres."""
    if "box_min" in f.attrs and "box_max" in f.attrs:
        return np.asarray(f.attrs["box_min"], float), np.asarray(f.attrs["box_max"], float), True
    lo = np.full(3, np.nan)
    hi = np.full(3, np.nan)
    if "planes" in f and "normal" in f["planes"]:
        for n, off in zip(f["planes/normal"][:], f["planes/offset"][:]):
            axis = int(np.argmax(np.abs(n)))
            if abs(abs(n[axis]) - 1.0) > 1e-12:
                continue
            if n[axis] > 0:        # spheres live where x_axis > offset
                lo[axis] = off
            else:                  # -x_axis > offset: x_axis < -offset
                hi[axis] = -off
    if np.all(np.isfinite(lo)) and np.all(np.isfinite(hi)):
        return lo, hi, True
    rmax = float(radius.max()) if radius.size else 0.0
    return pos.min(axis=0) - rmax, pos.max(axis=0) + rmax, False


def box_edges(lo, hi):
    corners = np.array([[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1])
                        for z in (lo[2], hi[2])])
    for i in range(8):
        for j in range(i + 1, 8):
            if np.sum(corners[i] != corners[j]) == 1:
                yield corners[i], corners[j]


def colours(args, pos, vel, view):
    """Values to colour by and their label, or (None, None)."""
    if args.color == "none":
        return None, None
    if args.color == "speed" and vel is not None:
        return np.linalg.norm(vel, axis=1), "speed"
    hidden = "xyz".replace(view[0], "").replace(view[1], "") if view != "3d" else "z"
    return pos[:, AXES[hidden]], "%s (height)" % hidden if view == "3d" else "%s (depth)" % hidden


def planes_of(f):
    """The run's planes as (normals (P, 3), offsets (P)): plane k is {x : n_k.x = offset_k}."""
    if "planes" in f and "normal" in f["planes"] and "offset" in f["planes"]:
        return np.asarray(f["planes/normal"][:], float), np.asarray(f["planes/offset"][:], float)
    return np.zeros((0, 3)), np.zeros(0)


def edge_on(planes, i, j):
    """The planes a projection onto axes i, j sees edge-on, as lines a u + b v = offset (u, v:
    coordinates i, j): those whose normal has no component along the hidden axis, to a
    billionth of its length (a deck's normal of [1, 0, 1] is exact; one of a rotated groove
    computed in a script is not, and a plane a hair off edge-on still shows as its line)."""
    if planes is None:
        return
    normals, offsets = planes
    hidden = 3 - i - j
    for n, off in zip(normals, offsets):
        if abs(n[hidden]) <= 1e-9 * np.linalg.norm(n) and np.hypot(n[i], n[j]) > 0:
            yield n[i], n[j], off


def draw_3d(fig, pos, radius, c, lo, hi, boxed, args, planes=None):
    ax = fig.add_subplot(projection="3d")
    span = hi - lo
    ax.set_box_aspect(span / span.max())
    # marker area in points^2 ~ (diameter in points)^2; the axes span about 0.6 of the figure
    # width for the longest side (perspective makes this approximate)
    pts_per_unit = 0.6 * args.size * 72.0 / float(span.max())
    size = (2.0 * radius * pts_per_unit) ** 2
    sc = ax.scatter(pos[:, 0], pos[:, 1], pos[:, 2], s=size, c=c,
                    cmap="viridis" if c is not None else None,
                    color=None if c is not None else "tab:blue",
                    depthshade=True, edgecolors="none")
    if boxed:
        for a, b in box_edges(lo, hi):
            ax.plot(*zip(a, b), color="0.4", linewidth=0.6)
    ax.set_xlim(lo[0], hi[0])
    ax.set_ylim(lo[1], hi[1])
    ax.set_zlim(lo[2], hi[2])
    ax.set_xlabel("x")
    ax.set_ylabel("y")
    ax.set_zlabel("z")
    # at most 5 ticks an axis: matplotlib's default put 7 on the hopper's 0.66 of x, their
    # labels overlapping in the perspective's foreshortening (a new user's, 2026-12-01)
    for axis in (ax.xaxis, ax.yaxis, ax.zaxis):
        axis.set_major_locator(matplotlib.ticker.MaxNLocator(nbins=4))
    # an axis far shorter than the longest (the hopper's groove: 0.16 across, 7 long) is a few
    # pixels long, where its tick labels fell on one another: no ticks; its extent goes under
    # the title (ax.short, which main reads)
    ax.short = []
    for k, name in enumerate("xyz"):
        if span[k] < 0.1 * span.max():
            (ax.xaxis, ax.yaxis, ax.zaxis)[k].set_ticks([])
            ax.short.append("%s %.3g .. %.3g" % (name, lo[k], hi[k]))
    return ax, sc


def colour_range(mappable, c, label):
    """Speeds from 0: with every sphere at rest (a settled pile) matplotlib's range for
    constant data ran from -0.1 to 0.1, negative speeds on the bar (until 2026-12-03)."""
    if label == "speed" and not np.any(c > 0.0):
        mappable.set_clim(0.0, 1.0)


def draw_2d(fig, pos, radius, c, lo, hi, boxed, args, planes=None):
    ax = fig.add_subplot()
    i, j = AXES[args.view[0]], AXES[args.view[1]]
    depth = AXES["xyz".replace(args.view[0], "").replace(args.view[1], "")]
    # far first, nearest drawn last: the viewer looks from the side the right-handed normal of
    # the view (its first axis across, its second up) points to, -y for xz (until 2026-12-03
    # every view sorted by the coordinate itself, and xz drew the back spheres over the front)
    toward = np.cross(np.eye(3)[i], np.eye(3)[j])[depth]
    order = np.argsort(toward * pos[:, depth], kind="stable")
    ec = EllipseCollection(2 * radius[order], 2 * radius[order], np.zeros(len(order)),
                           units="xy", offsets=pos[order][:, [i, j]],
                           offset_transform=ax.transData, cmap="viridis",
                           edgecolors="0.2", linewidths=0.2)
    if c is not None:
        ec.set_array(c[order])
    else:
        ec.set_facecolor("tab:blue")
    ax.add_collection(ec)
    if boxed:
        ax.add_patch(plt.Rectangle((lo[i], lo[j]), hi[i] - lo[i], hi[j] - lo[j], fill=False,
                                   edgecolor="0.4", linewidth=0.8))
    pad = 0.02 * max(hi[i] - lo[i], hi[j] - lo[j])
    ax.set_xlim(lo[i] - pad, hi[i] + pad)
    ax.set_ylim(lo[j] - pad, hi[j] + pad)
    ax.set_aspect("equal")
    # each plane seen edge-on as a line across the view (until 2026-12-02 none: the hopper's
    # groove in --view xz was spheres over nothing)
    for a, b, off in edge_on(planes, i, j):
        at = np.array([a, b]) * off / (a * a + b * b)   # the line's point nearest the origin
        ax.axline(at, at + np.array([-b, a]), color="0.3", linewidth=1.0)
    ax.set_xlabel(args.view[0])
    ax.set_ylabel(args.view[1])
    return ax, ec if c is not None else None


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter,
                                 epilog=__doc__.split("\n\n", 2)[2])
    ap.add_argument("run", help="an nbep-1 run file (RUN.h5)")
    ap.add_argument("--frames", default="0,-1",
                    help="frame indices, comma-separated; negative count from the end "
                    "(default 0,-1)")
    ap.add_argument("--out", help="folder for the images (default: beside the run file)")
    ap.add_argument("--view", default="3d", choices=["3d", "xy", "xz", "yz"])
    ap.add_argument("--color", default="speed", choices=["speed", "height", "none"])
    ap.add_argument("--size", type=float, default=6.0, help="figure width in inches")
    ap.add_argument("--dpi", type=int, default=150)
    args = ap.parse_args()

    try:
        run = h5py.File(args.run, "r")
    except OSError as e:  # h5py's text for these spans lines; errno names the reason
        if e.errno == errno.ENOENT:
            fail("%s: no such file" % args.run)
        fail("%s: %s" % (args.run, os.strerror(e.errno) if e.errno else str(e).splitlines()[0]))
    with run as f:
        if f.attrs.get("format") not in ("nbep-1", b"nbep-1"):
            fail("%s is not an nbep-1 run file" % args.run)
        if "frames/position" not in f:
            fail("%s has no positions (output.fields lacks \"position\")" % args.run)
        rows = f["frames/position"].shape[0]
        count = int(f["frames"].attrs.get("count", rows))
        count = min(count, rows, f["frames/step"].shape[0])
        if count == 0:
            fail("%s has no complete frame yet" % args.run)
        frames = parse_frames(args.frames, count)
        radius = f["spheres/radius"][:]
        has_vel = "frames/velocity" in f
        planes = planes_of(f)
        out = args.out or os.path.dirname(os.path.abspath(args.run))
        os.makedirs(out, exist_ok=True)
        stem = os.path.splitext(os.path.basename(args.run))[0]
        for k in frames:
            pos = f["frames/position"][k]
            vel = f["frames/velocity"][k] if has_vel else None
            step = int(f["frames/step"][k])
            t = float(f["frames/time"][k])
            lo, hi, boxed = box_of(f, pos, radius)
            c, label = colours(args, pos, vel, args.view)
            fig = plt.figure(figsize=(args.size, args.size * (0.85 if args.view == "3d" else 0.8)))
            draw = draw_3d if args.view == "3d" else draw_2d
            ax, mappable = draw(fig, pos, radius, c, lo, hi, boxed, args, planes)
            if c is not None and mappable is not None:
                colour_range(mappable, c, label)
                fig.colorbar(mappable, ax=ax, shrink=0.7, pad=0.1, label=label)
            title = "%s: step %d, t = %.4g, %d spheres" % (stem, step, t, len(radius))
            if getattr(ax, "short", None):
                title += "\n" + ", ".join(ax.short) + " (too short to tick)"
            ax.set_title(title, fontsize=10)
            view = "" if args.view == "3d" else "-" + args.view
            # another colouring, another name: --color height wrote over the speed picture of
            # the same frame and view (a new user's, 2026-12-01)
            view += "" if args.color == "speed" else "-" + args.color
            path = os.path.join(out, "%s-step-%06d%s.png" % (stem, step, view))
            fig.savefig(path, dpi=args.dpi, bbox_inches="tight")
            plt.close(fig)
            print(path)
    return 0


if __name__ == "__main__":
    sys.exit(main())
