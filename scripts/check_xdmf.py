#!/usr/bin/python3
"""Checks an XDMF sidecar (RUN.xmf) the way a reader would use it: the XML parses, it is one
temporal collection of Polyvertex grids with increasing times, and every HDF5 reference
(file:/dataset, relative to the sidecar's folder) resolves in the run file with the declared
shape, and every hyperslab selects an existing frame whose /frames/step and /frames/time are
the grid's step and time.

    scripts/check_xdmf.py RUN.xmf [--xml-only]
    pvpython scripts/check_xdmf.py RUN.xmf --paraview

--xml-only checks only that the XML is well-formed and shaped as above (no h5py needed).
--paraview (under ParaView's pvpython) also opens the sidecar with ParaView's XDMF reader and
checks that it sees every frame's time, one point per sphere at the frame's positions, and
the radius, mass and velocity arrays. Exit status 0 when all is well, 1 with one line per
problem otherwise."""
import argparse
import os
import sys
import xml.etree.ElementTree as ET


def numbers(text):
    return [int(x) for x in text.split()]


def paraview_problems(xmf, grids, files):
    """What ParaView's XDMF reader sees, against the run file, at the first and last frame."""
    import numpy as np
    from paraview import servermanager as sm
    from paraview.simple import XDMFReader
    from vtk.util.numpy_support import vtk_to_numpy

    problems = []
    reader = XDMFReader(FileNames=[os.path.abspath(xmf)])
    times = list(reader.TimestepValues or [])
    want = [float(g.find("Time").get("Value")) for g in grids]
    if len(want) == 1 and not times:
        times = want  # a single grid is not a time series to ParaView
    if times != want:
        problems.append("ParaView sees times %s, the sidecar has %s" % (times[:4], want[:4]))
        return problems
    f = next(iter(files.values()))
    for k in sorted({0, len(grids) - 1}):
        reader.UpdatePipeline(times[k])
        data = sm.Fetch(reader)
        pts = vtk_to_numpy(data.GetPoints().GetData())
        if not np.array_equal(pts, f["frames/position"][k]):
            problems.append("ParaView's points of frame %d differ from /frames/position[%d]" %
                            (k, k))
        arrays = data.GetPointData()
        for name, dset in (("radius", "spheres/radius"), ("mass", "spheres/mass"),
                           ("velocity", "frames/velocity")):
            if dset not in f:
                continue
            a = arrays.GetArray(name)
            want_a = f[dset][k] if dset.startswith("frames") else f[dset][:]
            if a is None or not np.array_equal(vtk_to_numpy(a), want_a):
                problems.append("ParaView's %s of frame %d differs from /%s" % (name, k, dset))
    return problems


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("xmf")
    ap.add_argument("--xml-only", action="store_true")
    ap.add_argument("--paraview", action="store_true")
    args = ap.parse_args()
    problems = []
    if not os.path.isfile(args.xmf):
        sys.stderr.write("check_xdmf.py: %s: no such file\n" % args.xmf)
        sys.exit(2)
    root = ET.parse(args.xmf).getroot()  # raises (exit 1) when not well-formed
    if root.tag != "Xdmf":
        problems.append("root element is %s, not Xdmf" % root.tag)
    series = root.findall("./Domain/Grid")
    if len(series) != 1 or series[0].get("CollectionType") != "Temporal":
        problems.append("expected one temporal collection under Domain")
        series = series[:1]
    grids = series[0].findall("./Grid") if series else []
    files = {}
    h5py = None
    if not args.xml_only:
        import h5py  # noqa: F811  (only when checking the data)
    folder = os.path.dirname(os.path.abspath(args.xmf))
    last_time = None
    for k, g in enumerate(grids):
        where = "frame %d (%s)" % (k, g.get("Name"))
        t = float(g.find("Time").get("Value"))
        if last_time is not None and not t > last_time:
            problems.append("%s: time %r does not increase" % (where, t))
        last_time = t
        topo = g.find("Topology")
        n = int(topo.get("NumberOfElements"))
        if topo.get("TopologyType") != "Polyvertex":
            problems.append("%s: topology is not Polyvertex" % where)
        slabs = [("position", g.find("Geometry/DataItem"))]
        for a in g.findall("Attribute"):
            item = a.find("DataItem")
            slabs.append((a.get("Name"), item))
        for name, item in slabs:
            if item.get("ItemType") == "HyperSlab":
                sel, data = item.findall("DataItem")
                start, stride, count = [numbers(sel.text)[i:i + 3] for i in (0, 3, 6)]
                if start[1:] != [0, 0] or stride != [1, 1, 1] or count != [1, n, 3]:
                    problems.append("%s: %s: bad hyperslab %s %s %s" %
                                    (where, name, start, stride, count))
            else:
                start, data = None, item
            ref = data.text.strip()
            fname, _, dset = ref.rpartition(":")
            dims = numbers(data.get("Dimensions"))
            if h5py is None:
                continue
            path = os.path.join(folder, fname)
            if path not in files:
                files[path] = h5py.File(path, "r")
            f = files[path]
            if dset not in f:
                problems.append("%s: %s: %s has no %s" % (where, name, fname, dset))
                continue
            ds = f[dset]
            if start is None:
                if list(ds.shape) != dims:
                    problems.append("%s: %s: %s has shape %s, declared %s" %
                                    (where, name, dset, ds.shape, dims))
                continue
            if list(ds.shape[1:]) != dims[1:] or ds.shape[0] < dims[0]:
                problems.append("%s: %s: %s has shape %s, declared %s" %
                                (where, name, dset, ds.shape, dims))
                continue
            if start[0] >= dims[0]:
                problems.append("%s: %s: frame %d past the declared %d" %
                                (where, name, start[0], dims[0]))
                continue
            step = g.get("Name").split()[-1]
            if g.get("Name").startswith("step ") and "/frames/step" in f:
                if int(f["/frames/step"][start[0]]) != int(step):
                    problems.append("%s: /frames/step[%d] is %d" %
                                    (where, start[0], f["/frames/step"][start[0]]))
            if "/frames/time" in f and float(f["/frames/time"][start[0]]) != t:
                problems.append("%s: /frames/time[%d] is %r, the sidecar says %r" %
                                (where, start[0], float(f["/frames/time"][start[0]]), t))
    if args.paraview and not problems and grids:
        problems += paraview_problems(args.xmf, grids, files)
    for p in problems:
        print("%s: %s" % (args.xmf, p))
    if not problems:
        print("%s: ok, %d frames%s%s" % (args.xmf, len(grids),
                                         "" if args.xml_only else ", every reference resolves",
                                         ", ParaView reads it" if args.paraview else ""))
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
