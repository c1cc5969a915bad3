"""The minimal OpenFOAM mesh that lets ParaView's built-in OpenFOAM reader open a case.

ParaView's reader (``vtkOpenFOAMReader``, opened through ``CASE/CASE.foam``) refuses a
case without ``constant/polyMesh`` ("contains no meshes") and looks for clouds only
beside one. sphfoam needs no mesh, so :func:`write_foam_files` writes the smallest
valid one: a single hexahedral cell spanning the particle domain (the box outside which
particles are removed) and one particle spacing thick in z around z = 0, as a 2-D
OpenFOAM case is one cell thick. Its four sides form the patch ``sides``; the two
z-faces the ``empty`` patch ``frontAndBack``. Every particle is in cell 0 (the cell
index of the ``positions`` records). In ParaView, untick ``internalMesh`` under Mesh
Regions to see the particles alone (``lagrangian/particles``).
"""

from __future__ import annotations

from pathlib import Path

__all__ = ["write_foam_files", "write_poly_mesh", "foam_file"]

# hex vertices 0..7 in OpenFOAM's order (bottom face z0 anticlockwise, then top at z1);
# faces listed so that the right-hand normal points out of the cell (owner = cell 0)
_FACES = [
    (0, 4, 7, 3),  # x min   \
    (1, 2, 6, 5),  # x max    | sides
    (0, 1, 5, 4),  # y min    |
    (3, 7, 6, 2),  # y max   /
    (0, 3, 2, 1),  # z min   \ frontAndBack
    (4, 5, 6, 7),  # z max   /
]


def _header(cls: str, name: str, note: str | None = None) -> str:
    lines = ["FoamFile", "{", "    version     2.0;", "    format      ascii;",
             f"    class       {cls};"]
    if note:
        lines.append(f'    note        "{note}";')
    lines += ['    location    "constant/polyMesh";', f"    object      {name};", "}",
              "// " + "* " * 37 + "//", "", ""]
    return "\n".join(lines)


def write_poly_mesh(case_dir: str | Path, lo, hi, thickness: float) -> Path:
    """Write ``constant/polyMesh`` (points, faces, owner, neighbour, boundary): one cell
    covering ``lo``..``hi`` in x, y and ``-thickness/2``..``thickness/2`` in z (a 2-D
    case), or ``lo``..``hi`` (a 3-D case: ``lo``, ``hi`` with three components)."""
    mesh = Path(case_dir) / "constant" / "polyMesh"
    mesh.mkdir(parents=True, exist_ok=True)
    three = len(lo) == 3
    if three:                      # a 3-D case: the cell spans the domain in z too
        (x0, y0, z0), (x1, y1, z1) = lo, hi
    else:
        (x0, y0), (x1, y1) = lo, hi
        z0, z1 = -0.5 * thickness, 0.5 * thickness
    pts = [(x0, y0, z0), (x1, y0, z0), (x1, y1, z0), (x0, y1, z0),
           (x0, y0, z1), (x1, y0, z1), (x1, y1, z1), (x0, y1, z1)]
    files = {
        "points": ("vectorField", None,
                   "8\n(\n" + "".join("(%.17g %.17g %.17g)\n" % p for p in pts) + ")\n"),
        "faces": ("faceList", None,
                  "6\n(\n" + "".join("4(%d %d %d %d)\n" % f for f in _FACES) + ")\n"),
        "owner": ("labelList", "nPoints:8 nCells:1 nFaces:6 nInternalFaces:0",
                  "6\n(\n" + "0\n" * 6 + ")\n"),
        "neighbour": ("labelList", "nPoints:8 nCells:1 nFaces:6 nInternalFaces:0",
                      "0\n(\n)\n"),
        "boundary": ("polyBoundaryMesh", None, _SIDES_3D if three else
                     "2\n(\n"
                     "    sides\n    {\n        type            patch;\n"
                     "        nFaces          4;\n        startFace       0;\n    }\n"
                     "    frontAndBack\n    {\n        type            empty;\n"
                     "        inGroups        1(empty);\n"
                     "        nFaces          2;\n        startFace       4;\n    }\n"
                     ")\n"),
    }
    for name, (cls, note, body) in files.items():
        (mesh / name).write_text(_header(cls, name, note) + body)
    return mesh


#: a 3-D case's one cell: all six faces are the patch ``sides``
_SIDES_3D = ("1\n(\n    sides\n    {\n        type            patch;\n"
             "        nFaces          6;\n        startFace       0;\n    }\n)\n")


def foam_file(case_dir: str | Path) -> Path:
    """``CASE/CASE.foam``: the (empty) file ParaView opens a case by."""
    case_dir = Path(case_dir).resolve()
    return case_dir / f"{case_dir.name}.foam"


def write_foam_files(case_dir: str | Path, lo, hi, thickness: float) -> Path:
    """The one-cell mesh and ``CASE.foam``; returns the ``.foam`` file's path."""
    write_poly_mesh(case_dir, lo, hi, thickness)
    f = foam_file(case_dir)
    if not f.exists():
        f.write_text("")
    return f

