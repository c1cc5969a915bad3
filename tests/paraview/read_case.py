"""Open a sphfoam case with ParaView's built-in OpenFOAM reader and report what it sees.

Run with ParaView's Python (``xvfb-run -a pvpython read_case.py CASE/CASE.foam OUT.json
[--screenshot PNG]``); used by tests/test_paraview.py. Writes a JSON file with the
mesh regions, the lagrangian arrays (name -> number of components), the times, and for
every time the particle points and every array's values, as ParaView read them.
"""

import json
import sys

from paraview import servermanager as sm
from paraview.simple import OpenFOAMReader
from vtkmodules.util.numpy_support import vtk_to_numpy

foam, out = sys.argv[1], sys.argv[2]
shot = sys.argv[sys.argv.index("--screenshot") + 1] if "--screenshot" in sys.argv else None

# t = 0 holds the set-up particles: show it too (ParaView skips it by default, as it
# does for any OpenFOAM case)
r = OpenFOAMReader(FileName=foam)
r.SkipZeroTime = 0
r.Refresh()                             # re-lists the times (as the GUI's Reload does)
r.UpdatePipelineInformation()
report = {
    "regions": list(r.MeshRegions.Available),
    "lagrangian_arrays": list(r.LagrangianArrays.Available),
    "times": list(r.TimestepValues),
    "data": {},
}
r.MeshRegions = ["lagrangian/particles"]
r.LagrangianArrays = list(r.LagrangianArrays.Available)
for t in report["times"]:
    r.UpdatePipeline(t)
    mb = sm.Fetch(r)
    cloud = mb.GetBlock(0).GetBlock(0)  # lagrangian / particles
    cd = cloud.GetCellData()
    entry = {"points": vtk_to_numpy(cloud.GetPoints().GetData()).tolist(),
             "n_cells": cloud.GetNumberOfCells(), "arrays": {}}
    for k in range(cd.GetNumberOfArrays()):
        a = cd.GetArray(k)
        entry["arrays"][a.GetName()] = {"components": a.GetNumberOfComponents(),
                                        "values": vtk_to_numpy(a).tolist()}
    report["data"][repr(t)] = entry

if shot:
    from paraview.simple import (ColorBy, GetActiveViewOrCreate, GetColorTransferFunction,
                                 GetParaViewVersion, GetScalarBar, SaveScreenshot, Show, Text)

    w, h = 1600, 560
    view = GetActiveViewOrCreate("RenderView")
    view.ViewSize = [w, h]
    t_shot = report["times"][-1]
    view.ViewTime = t_shot
    view.OrientationAxesVisibility = 0
    view.Background = [1, 1, 1]
    try:  # ParaView >= 5.10 keeps a palette; use the plain background set above
        view.UseColorPaletteForBackground = 0
    except AttributeError:
        pass
    disp = Show(r, view)
    disp.SetRepresentationType("Points")
    disp.PointSize = 2.5
    ColorBy(disp, ("CELLS", "U", "Magnitude"))
    lut = GetColorTransferFunction("U")
    lut.ApplyPreset("Turbo", True)
    disp.RescaleTransferFunctionToDataRange(False, True)
    disp.SetScalarBarVisibility(view, True)
    bar = GetScalarBar(lut, view)
    bar.Title, bar.ComponentTitle = "U magnitude", "(m/s)"
    bar.TitleColor = bar.LabelColor = [0, 0, 0]
    bar.Orientation, bar.WindowLocation = "Horizontal", "Upper Right Corner"
    v = GetParaViewVersion()
    label = Text(Text=f"ParaView {v.major}.{v.minor}, OpenFOAM reader: {foam.split('/')[-1]}, "
                      f"lagrangian/particles, t = {t_shot:g} s")
    ld = Show(label, view)
    ld.Color, ld.FontSize, ld.WindowLocation = [0, 0, 0], 14, "Upper Left Corner"
    b = sm.Fetch(r).GetBlock(0).GetBlock(0).GetBounds()
    cx, cy = 0.5 * (b[0] + b[1]), 0.5 * (b[2] + b[3])
    view.CameraParallelProjection = 1
    view.CameraPosition, view.CameraFocalPoint = [cx, cy, 10], [cx, cy, 0]
    view.CameraViewUp = [0, 1, 0]
    view.CameraParallelScale = 1.08 * max(0.5 * (b[3] - b[2]), 0.5 * (b[1] - b[0]) * h / w)
    SaveScreenshot(shot, view, ImageResolution=[w, h])
    report["screenshot"] = shot

with open(out, "w") as fh:
    json.dump(report, fh)
print("times", report["times"])
print("regions", report["regions"])
print("lagrangian arrays", report["lagrangian_arrays"])
