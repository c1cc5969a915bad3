"""Cloning a case and editing its dictionaries (tutorial variants, studies, tests)."""

from __future__ import annotations

import shutil
from pathlib import Path

from sphfoam.case import foamdict

#: what a clone leaves behind: results of the source case, and the mesh and .foam file that
#: setup writes for ParaView (the clone writes its own)
RESULTS = ("[1-9]*", "0.*", "postProcessing", "VTK", "log.*", "lagrangian", "uniform",
           "compare", "runUp", "study", "studySmall", "stability", "polyMesh", "*.foam",
           # a running case's lock and the remains of interrupted writes (sphfoam.io.timedirs)
           ".sphfoam.lock", ".*.writing-*", ".*.replaced-*")


def set_entry(case: Path, rel: str, key: str, value) -> None:
    """Set ``a.b.c`` in ``case/rel`` (written back in OpenFOAM syntax); None removes it."""
    path = Path(case) / rel
    d = foamdict.read(path)
    header = d.pop("FoamFile", None)
    node = d
    *parents, last = key.split(".")
    for k in parents:
        node = node.setdefault(k, {})
    if value is None:
        node.pop(last, None)
    else:
        node[last] = value
    foamdict.write(path, d, header=header)


def clone_case(src: Path, dst: Path, edits: dict | None = None, ignore=()) -> Path:
    """Copy the dictionaries of ``src`` (no results, nothing matching ``ignore``) to ``dst``
    and apply ``{"file:key.path": value}`` edits."""
    import fnmatch

    src, dst = Path(src).resolve(), Path(dst).absolute()
    rd = dst.resolve()
    if rd == src or rd in src.parents:
        raise ValueError(f"cannot clone case {src} into {dst}: that is the case itself or a "
                         "folder holding it")
    if src in rd.parents:
        first = rd.relative_to(src).parts[0]
        if not any(fnmatch.fnmatch(first, pat) for pat in (*RESULTS, *ignore)):
            raise ValueError(f"cannot clone case {src} into {dst}, a folder inside it: the "
                             f"copy would contain itself; choose a folder outside the case "
                             f"(or one named like a result folder, such as {src / 'study'})")
    if dst.is_symlink():
        raise ValueError(f"{dst} is a symbolic link: not replaced")
    if dst.exists():
        shutil.rmtree(dst)
    shutil.copytree(src, dst, ignore=shutil.ignore_patterns(*RESULTS, *ignore))
    for where, value in (edits or {}).items():
        rel, key = where.split(":")
        set_entry(dst, rel, key, value)
    return dst
