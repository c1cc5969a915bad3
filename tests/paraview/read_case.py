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
    from paraview.simple import (ColorBy, GetActiveViewOrCreate, GetDisplayProperties,
                                 ResetCamera, SaveScreenshot, Show)

    view = GetActiveViewOrCreate("RenderView")
    view.ViewSize = [1400, 500]
    view.ViewTime = report["times"][-1]
    view.OrientationAxesVisibility = 0
    disp = Show(r, view)
    disp.SetRepresentationType("Points")
    disp.PointSize = 3
    ColorBy(disp, ("CELLS", "U", "Magnitude"))
    disp.RescaleTransferFunctionToDataRange(True, False)
    disp.SetScalarBarVisibility(view, True)
    view.CameraPosition = [1.25, 0.25, 10]
    view.CameraFocalPoint = [1.25, 0.25, 0]
    view.CameraViewUp = [0, 1, 0]
    ResetCamera(view)
    SaveScreenshot(shot, view, ImageResolution=[1400, 500])
    report["screenshot"] = shot

with open(out, "w") as fh:
    json.dump(report, fh)
print("times", report["times"])
print("regions", report["regions"])
print("lagrangian arrays", report["lagrangian_arrays"])
