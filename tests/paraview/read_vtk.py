"""Open ``sphfoam export vtk`` output in ParaView and report what it sees.

``pvpython read_vtk.py VTK/CASE.pvd VTK/CASE_fluid.vtp.series OUT.json``; used by
tests/test_paraview.py. Reports the times of both, and per time the block names and point
counts of the .pvd's multiblock and the TimeValue and point count of the series' file.
"""

import json
import sys

from paraview import servermanager as sm
from paraview.simple import OpenDataFile

pvd, series, out = sys.argv[1:4]
r, s = OpenDataFile(pvd), OpenDataFile(series)
rep = {"pvd_times": list(r.TimestepValues), "series_times": list(s.TimestepValues),
       "pvd": {}, "series": {}}
for t in rep["pvd_times"]:
    r.UpdatePipeline(t)
    mb = sm.Fetch(r)
    rep["pvd"][repr(t)] = {mb.GetMetaData(i).Get(mb.NAME()): mb.GetBlock(i).GetNumberOfPoints()
                           for i in range(mb.GetNumberOfBlocks())}
for t in rep["series_times"]:
    s.UpdatePipeline(t)
    poly = sm.Fetch(s)
    rep["series"][repr(t)] = {"points": poly.GetNumberOfPoints(),
                              "TimeValue": poly.GetFieldData().GetArray("TimeValue").GetValue(0),
                              "U_components": poly.GetPointData().GetArray("U")
                              .GetNumberOfComponents()}
with open(out, "w") as fh:
    json.dump(rep, fh)
print(json.dumps(rep))
