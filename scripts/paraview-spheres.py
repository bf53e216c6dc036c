#!/usr/bin/env pvpython
"""Renders one frame of an nbep run through its XDMF sidecar with ParaView: every sphere at its
true radius (Point Gaussian, scaled by the radius array), coloured by speed, inside the
outline of the spheres' extent. The same settings, made by hand in the ParaView GUI, are in
README.md, *ParaView and VisIt: the XDMF sidecar*.

    pvpython scripts/paraview-spheres.py RUN.xmf OUT.png [--frame -1] [--size 900x700]

Without a display (a cluster node, a container): xvfb-run -a pvpython scripts/... or
pvpython --force-offscreen-rendering where ParaView was built for it (EGL or OSMesa)."""
import argparse

from paraview.simple import (ColorBy, CreateView, GetColorTransferFunction, GetScalarBar,
                             Outline, SaveScreenshot, Show, XDMFReader)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("xmf")
    ap.add_argument("png")
    ap.add_argument("--frame", type=int, default=-1, help="frame index; -1 = the last")
    ap.add_argument("--size", default="900x700", help="image size WxH in pixels")
    args = ap.parse_args()
    w, h = (int(x) for x in args.size.split("x"))

    reader = XDMFReader(FileNames=[args.xmf])
    times = list(reader.TimestepValues or [0.0])
    view = CreateView("RenderView")
    view.ViewSize = [w, h]
    view.ViewTime = times[args.frame]
    view.OrientationAxesVisibility = 0
    spheres = Show(reader, view)
    # Point Gaussian with the scale array used as is: each point becomes a sphere of radius
    # `radius` in the data's units (the scale function would remap the array's range).
    spheres.SetRepresentationType("Point Gaussian")
    spheres.ShaderPreset = "Sphere"
    spheres.GaussianRadius = 1.0
    spheres.ScaleByArray = 1
    spheres.SetScaleArray = ["POINTS", "radius"]
    spheres.UseScaleFunction = 0
    if reader.PointData.GetArray("velocity") is not None:
        ColorBy(spheres, ("POINTS", "velocity", "Magnitude"))
        spheres.RescaleTransferFunctionToDataRange(False, True)
        lut = GetColorTransferFunction("velocity")
        lut.ApplyPreset("Viridis (matplotlib)", True)
        bar = GetScalarBar(lut, view)
        bar.Title = "speed"
        bar.ComponentTitle = ""
        bar.Visibility = 1
    Show(Outline(Input=reader), view)
    # z up (gravity along -z in the examples), looking from the front right and above
    x0, x1, y0, y1, z0, z1 = reader.GetDataInformation().GetBounds()
    centre = [(x0 + x1) / 2, (y0 + y1) / 2, (z0 + z1) / 2]
    size = max(x1 - x0, y1 - y0, z1 - z0, 1e-300)
    view.CameraFocalPoint = centre
    view.CameraPosition = [centre[0] + 1.6 * size, centre[1] - 1.9 * size, centre[2] + 1.1 * size]
    view.CameraViewUp = [0.0, 0.0, 1.0]
    view.ResetCamera()
    SaveScreenshot(args.png, view, ImageResolution=[w, h])
    print(args.png)


if __name__ == "__main__":
    main()
