"""Export particle states to VTK XML files for ParaView.

``export_case`` writes, for every time directory with particles (``<t>`` its name)::

    VTK/<case>_<t>/fluid.vtp     the fluid particles
    VTK/<case>_<t>/walls.vtp     the wall particles (empty where the boundary has none)
    VTK/<case>_<t>.vtm           a multiblock of the two, blocks named fluid and walls
    VTK/<case>.pvd               the time series of the .vtm files (open this one)
    VTK/<case>_fluid.vtp.series  the fluid alone as a time series (and _walls likewise)
    VTK/<case>_0.unsettled.vtm   the layout before settling, when the case was settled
                                 (``0.unsettled/``, sphfoam.setup.settling; not in the series)

Each ``.vtp`` is a vtkPolyData with one vertex cell per particle (so the Surface
representation shows the points) and stores its time as ``TimeValue`` field data.
Vectors are 3-component point data: ``U``, and the component fields listed in
:data:`VECTOR_PAIRS` (``x0, y0`` -> ``X0``, ...); a 2-D case's with z = 0, a 3-D case's
(``dimension 3;`` in system/particleDict) points and vectors with their z components. An export replaces the
previous one: files of times not exported this time are removed, so ``-t`` never leaves
stale files behind.
"""

from __future__ import annotations

import json
import math
import re
import shutil
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
from vtkmodules.util.numpy_support import numpy_to_vtk, numpy_to_vtkIdTypeArray
from vtkmodules.vtkCommonCore import vtkPoints
from vtkmodules.vtkCommonDataModel import vtkCellArray, vtkPolyData
from vtkmodules.vtkIOXML import vtkXMLPolyDataWriter

from ..case.times import list_times
from .timedirs import UNSETTLED
from .fields import has_particles, read_state

__all__ = ["write_vtp", "export_case", "VECTOR_PAIRS", "BLOCKS"]

#: scalar fields exported as one 3-vector: vector name -> (x, y, z component); a 2-D case
#: has no z component (0 in the file)
VECTOR_PAIRS = {
    "X0": ("x0", "y0", "z0"),           # a moving wall particle's rest position
    "n": ("nx", "ny", "nz"),            # wall normal (boundary models with wall_fields)
    "U_0": ("Ux_0", "Uy_0", "Uz_0"),    # an integrator's previous-step velocity
}

#: the blocks of each time: name -> which particles (from the ``type`` field)
BLOCKS = ("fluid", "walls")


def _pad3(a: np.ndarray) -> np.ndarray:
    """(N, 2) -> (N, 3) float64 with z = 0."""
    out = np.zeros((len(a), 3))
    out[:, : a.shape[1]] = a
    return out


def _vectorise(fields: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
    """Replace the component fields of :data:`VECTOR_PAIRS` by (N, 2) vectors, or (N, 3)
    where the z component is there too (a 3-D case)."""
    out = dict(fields)
    for vec, (cx, cy, cz) in VECTOR_PAIRS.items():
        if cx in out and cy in out and vec not in out:
            comps = [out.pop(cx), out.pop(cy)] + ([out.pop(cz)] if cz in out else [])
            out[vec] = np.column_stack(comps)
    return out


def write_vtp(path: str | Path, fields: dict[str, np.ndarray], time: float | None = None) -> None:
    """Write particles to a binary (appended, zlib-compressed) ``.vtp`` file.

    ``fields["positions"]`` (N, 2) gives the points (z = 0), (N, 3) the 3-D points. Every
    other field
    becomes point data: (N,) arrays as scalars (integers as int64), (N, 2)
    arrays as 3-component vectors with z = 0, (N, 3) arrays as they are.
    ``time`` is stored as the ``TimeValue`` field data ParaView reads.
    """
    if "positions" not in fields:
        raise KeyError("write_vtp needs a 'positions' field")
    pos = np.asarray(fields["positions"], dtype=np.float64)
    if pos.ndim != 2 or pos.shape[1] not in (2, 3):
        raise ValueError(f"positions must have shape (N, 2) or (N, 3), got {pos.shape}")
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
    if time is not None:
        tv = numpy_to_vtk(np.array([float(time)]), deep=True)
        tv.SetName("TimeValue")
        poly.GetFieldData().AddArray(tv)

    writer = vtkXMLPolyDataWriter()
    writer.SetFileName(str(path))
    writer.SetInputData(poly)
    writer.SetDataModeToAppended()
    writer.EncodeAppendedDataOff()
    writer.SetCompressorTypeToZLib()
    if not writer.Write():
        raise OSError(f"failed to write {path}")


def _dimension(case_dir: Path) -> int | None:
    """The case's ``dimension`` (system/particleDict), None where there is no particleDict
    (then each time directory's positions decide, sphfoam.io.fields.read_state)."""
    from ..case.case import Case

    if not (case_dir / "system" / "particleDict").is_file():
        return None
    return Case(case_dir).dimension


def _time_value(folder: Path) -> float:
    """The exact time of a time directory (``uniform/time``), else its name."""
    from ..case import foamdict

    f = folder / "uniform" / "time"
    if f.is_file():
        try:
            return float(foamdict.read(f)["value"])
        except (KeyError, ValueError, TypeError):
            pass
    return float(folder.name)


def _split(fields: dict[str, np.ndarray]) -> dict[str, dict[str, np.ndarray]]:
    """The fields of each block: fluid (type 0) and walls (every other type)."""
    kind = np.asarray(fields.get("type", np.zeros(len(fields["positions"]), dtype=np.int64)))
    masks = {"fluid": kind == 0, "walls": kind != 0}
    return {b: {k: np.asarray(a)[masks[b]] for k, a in fields.items()} for b in BLOCKS}


def _previous_outputs(out_dir: Path, name: str) -> list[Path]:
    """What an earlier export of case ``name`` wrote into ``out_dir`` (this version's
    ``<name>_<t>.vtm`` + ``<name>_<t>/``, older versions' ``<name>_<i>.vtp``)."""
    pat = re.compile(re.escape(name) + r"_[+-]?(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?(\.vtm|\.vtp)?$")
    found = [p for p in out_dir.iterdir() if pat.match(p.name)
             and (p.is_dir() or p.suffix in (".vtm", ".vtp"))]
    found += [out_dir / f"{name}_{b}.vtp.series" for b in BLOCKS]
    found += [out_dir / f"{name}_{UNSETTLED}", out_dir / f"{name}_{UNSETTLED}.vtm"]
    found.append(out_dir / f"{name}.pvd")
    return [p for p in found if p.exists()]


def _write_xml(root: ET.Element, path: Path) -> None:
    ET.indent(root)
    ET.ElementTree(root).write(path, encoding="utf-8", xml_declaration=True)


def _write_vtm(out_dir: Path, stem: str, folder: Path, t: float,
               dim: int | None = None) -> list[tuple[str, str]]:
    """``<stem>.vtm`` and its blocks ``<stem>/<block>.vtp`` from a time directory of a case
    of dimension ``dim``; returns (block, relative path) of each."""
    (out_dir / stem).mkdir()
    vtm = ET.Element("VTKFile", type="vtkMultiBlockDataSet", version="1.0",
                     byte_order="LittleEndian")
    mb = ET.SubElement(vtm, "vtkMultiBlockDataSet")
    out = []
    for i, (block, f) in enumerate(_split(_vectorise(read_state(folder, dim=dim))).items()):
        rel = f"{stem}/{block}.vtp"
        write_vtp(out_dir / rel, f, time=t)
        ET.SubElement(mb, "DataSet", index=str(i), name=block, file=rel)
        out.append((block, rel))
    _write_xml(vtm, out_dir / f"{stem}.vtm")
    return out


def export_case(
    case_dir: str | Path,
    times: list[float] | None = None,
    out_dir_name: str = "VTK",
) -> Path:
    """Export every time directory with particles (or only ``times``) to VTK.

    Writes the files listed in the module docstring and returns the ``.pvd`` path.
    Raises ``FileNotFoundError`` (naming the case and the times it has) when there is
    nothing to export; nothing is written or removed then.
    """
    case_dir = Path(case_dir).resolve()
    name = case_dir.name
    out_dir = case_dir / out_dir_name
    dim = _dimension(case_dir)

    available = [(t, d) for t, d in list_times(case_dir) if has_particles(d)]
    if not available:
        raise FileNotFoundError(
            f"{case_dir}: no time directory holds particles, so there is nothing to export; "
            f"run 'sphfoam setup {case_dir}' or 'sphfoam run {case_dir}' first")
    if times is None:
        selected = available
    else:
        selected = [(t, d) for t, d in available
                    if any(math.isclose(t, s, rel_tol=1e-9, abs_tol=1e-12) for s in times)]
        missing = [s for s in times if not any(
            math.isclose(t, s, rel_tol=1e-9, abs_tol=1e-12) for t, _ in available)]
        if missing:
            raise FileNotFoundError(
                f"{case_dir}: no time directory with particles at "
                + ", ".join(f"{s:g}" for s in missing)
                + "; have: " + ", ".join(d.name for _, d in available))

    out_dir.mkdir(parents=True, exist_ok=True)
    for p in _previous_outputs(out_dir, name):
        shutil.rmtree(p) if p.is_dir() else p.unlink()

    pvd = ET.Element("VTKFile", type="Collection", version="0.1", byte_order="LittleEndian")
    coll = ET.SubElement(pvd, "Collection")
    series = {b: [] for b in BLOCKS}
    for _, d in selected:
        t = _time_value(d)
        stem = f"{name}_{d.name}"
        for block, rel in _write_vtm(out_dir, stem, d, t, dim):
            series[block].append({"name": rel, "time": t})
        ET.SubElement(coll, "DataSet", timestep=repr(t), group="", part="0", file=f"{stem}.vtm")
    if times is None and has_particles(case_dir / UNSETTLED):
        # the layout before settling (sphfoam.setup.settling): beside the series, not in it
        _write_vtm(out_dir, f"{name}_{UNSETTLED}", case_dir / UNSETTLED, 0.0, dim)
    for block, files in series.items():
        (out_dir / f"{name}_{block}.vtp.series").write_text(
            json.dumps({"file-series-version": "1.0", "files": files}, indent=1))
    path = out_dir / f"{name}.pvd"
    _write_xml(pvd, path)
    return path
