"""Export particle states to VTK XML files for ParaView.

Each time directory with particles becomes one ``.vtp`` (vtkPolyData with one
vertex cell per particle, so the Surface representation shows the points);
a ``.pvd`` collection ties them together as a time series.
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
from vtkmodules.util.numpy_support import numpy_to_vtk, numpy_to_vtkIdTypeArray
from vtkmodules.vtkCommonCore import vtkPoints
from vtkmodules.vtkCommonDataModel import vtkCellArray, vtkPolyData
from vtkmodules.vtkIOXML import vtkXMLPolyDataWriter

from ..case.times import list_times
from .fields import has_particles, read_state

__all__ = ["write_vtp", "export_case"]


def _pad3(a: np.ndarray) -> np.ndarray:
    """(N, 2) -> (N, 3) float64 with z = 0."""
    out = np.zeros((len(a), 3))
    out[:, : a.shape[1]] = a
    return out


def write_vtp(path: str | Path, fields: dict[str, np.ndarray]) -> None:
    """Write particles to a binary (appended, zlib-compressed) ``.vtp`` file.

    ``fields["positions"]`` (N, 2) gives the points (z = 0). Every other field
    becomes point data: (N,) arrays as scalars (integers as int64), (N, 2)
    arrays as 3-component vectors with z = 0, (N, 3) arrays as they are.
    """
    if "positions" not in fields:
        raise KeyError("write_vtp needs a 'positions' field")
    pos = np.asarray(fields["positions"], dtype=np.float64)
    if pos.ndim != 2 or pos.shape[1] not in (2, 3):
        raise ValueError(f"positions must have shape (N, 2), got {pos.shape}")
    n = len(pos)

    points = vtkPoints()
    points.SetData(numpy_to_vtk(_pad3(pos), deep=True))
    cells = vtkCellArray()
    cells.SetData(
        numpy_to_vtkIdTypeArray(np.arange(n + 1, dtype=np.int64), deep=True),
        numpy_to_vtkIdTypeArray(np.arange(n, dtype=np.int64), deep=True),
    )
    poly = vtkPolyData()
    poly.SetPoints(points)
    poly.SetVerts(cells)

    pd = poly.GetPointData()
    for name, arr in fields.items():
        if name == "positions":
            continue
        a = np.asarray(arr)
        if len(a) != n or a.ndim not in (1, 2) or (a.ndim == 2 and a.shape[1] not in (2, 3)):
            raise ValueError(f"field {name!r}: shape {a.shape} does not fit {n} particles")
        if a.dtype.kind in "biu":
            a = a.astype(np.int64)
        else:
            a = a.astype(np.float64)
            if a.ndim == 2:
                a = _pad3(a)
        va = numpy_to_vtk(np.ascontiguousarray(a), deep=True)
        va.SetName(name)
        pd.AddArray(va)
        if name == "U" and a.ndim == 2:
            pd.SetActiveVectors(name)

    writer = vtkXMLPolyDataWriter()
    writer.SetFileName(str(path))
    writer.SetInputData(poly)
    writer.SetDataModeToAppended()
    writer.EncodeAppendedDataOff()
    writer.SetCompressorTypeToZLib()
    if not writer.Write():
        raise OSError(f"failed to write {path}")


def export_case(
    case_dir: str | Path,
    times: list[float] | None = None,
    out_dir_name: str = "VTK",
) -> Path:
    """Export every time directory with particles (or only ``times``) to VTK.

    Writes ``<case>/<out_dir_name>/<caseName>_<i>.vtp`` (i = 0, 1, ... in time
    order) and the collection ``<caseName>.pvd``, whose path is returned.
    """
    case_dir = Path(case_dir).resolve()
    name = case_dir.name
    out_dir = case_dir / out_dir_name
    out_dir.mkdir(parents=True, exist_ok=True)

    selected = [
        (t, d)
        for t, d in list_times(case_dir)
        if has_particles(d)
        and (times is None or any(math.isclose(t, s, rel_tol=1e-9, abs_tol=1e-12) for s in times))
    ]

    root = ET.Element("VTKFile", type="Collection", version="0.1", byte_order="LittleEndian")
    coll = ET.SubElement(root, "Collection")
    for i, (t, d) in enumerate(selected):
        fname = f"{name}_{i}.vtp"
        write_vtp(out_dir / fname, read_state(d))
        ET.SubElement(coll, "DataSet", timestep=repr(t), group="", part="0", file=fname)
    ET.indent(root)
    pvd = out_dir / f"{name}.pvd"
    ET.ElementTree(root).write(pvd, encoding="utf-8", xml_declaration=True)
    return pvd
