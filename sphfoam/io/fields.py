"""Particle fields stored in time directories, laid out like an OpenFOAM cloud.

Each field is one file ``<case>/<time>/lagrangian/particles/<name>``::

    FoamFile
    {
        version     2.0;
        format      binary;
        arch        "LSB;label=64;scalar=64";
        class       scalarField;
        location    "0.5/lagrangian/particles";
        object      rho;
    }

    N
    (
    <N values: one per line in ascii, raw little-endian bytes in binary>
    )
    ;

Supported classes: ``scalarField`` (float64, shape ``(N,)``), ``vector2DField``
(float64, ``(N, 2)``) and ``labelField`` (int64, ``(N,)``). The reader also
accepts ``vectorField`` (``(N, 3)``), the uniform form ``N{value}``, comments,
and binary files written with 32-bit labels/scalars or big-endian data.

A time directory (:func:`write_state`) is written the way OpenFOAM writes a cloud of a 2-D
case, so that ParaView's built-in OpenFOAM reader opens it: ``positions`` in the
``Cloud<passiveParticle>`` form ``(x y 0) celli`` (the pre-v1706 layout, which ESI's
OpenFOAM still writes beside its barycentric ``coordinates`` file and which ParaView
reads; the OpenFOAM Foundation's barycentric ``positions`` it cannot), and every
2-vector as a ``vectorField`` with z = 0. :func:`read_state` gives the in-plane
``(N, 2)`` arrays back bit for bit, and still reads the older ``vector2DField`` files.
"""

from __future__ import annotations

import os
import re
import threading
from pathlib import Path

import numpy as np

__all__ = ["write_field", "read_field", "write_state", "read_state", "has_particles", "CLOUD_DIR",
           "write_positions", "write_vectors", "POSITIONS_CLASS", "field_header", "upgrade_state"]

#: Sub-path of a time directory holding the particle fields.
CLOUD_DIR = Path("lagrangian") / "particles"

# class name -> (kind, components); kind is "scalar" or "label".
_CLASSES = {
    "scalarField": ("scalar", 1),
    "vector2DField": ("scalar", 2),
    "vectorField": ("scalar", 3),
    "labelField": ("label", 1),
}

_WS_COMMENT = re.compile(rb"(?:\s+|//[^\n]*|/\*.*?\*/)*", re.S)
_ENTRY = re.compile(rb'([A-Za-z_][\w.:]*)\s+((?:"[^"]*"|[^;"{}])*);')
_INT = re.compile(rb"\d+")
_PARENS = bytes.maketrans(b"()", b"  ")

#: FoamFile class of a cloud's ``positions`` file (one ``(x y z) celli`` record per particle)
POSITIONS_CLASS = "Cloud<passiveParticle>"


# ----------------------------------------------------------------------------- writing
def _class_of(a: np.ndarray) -> tuple[str, np.ndarray]:
    """FoamFile class and the contiguous little-endian array to write."""
    if a.dtype.kind in "biu":
        if a.ndim == 1:
            return "labelField", np.ascontiguousarray(a, dtype="<i8")
    elif a.dtype.kind == "f":
        if a.ndim == 1:
            return "scalarField", np.ascontiguousarray(a, dtype="<f8")
        if a.ndim == 2 and a.shape[1] == 2:
            return "vector2DField", np.ascontiguousarray(a, dtype="<f8")
    raise ValueError(
        f"unsupported field: dtype {a.dtype}, shape {a.shape}; "
        "expected float (N,), float (N, 2) or integer (N,)"
    )


def _header(cls: str, fmt: str, location: str, name: str) -> str:
    lines = ["FoamFile", "{", "    version     2.0;", f"    format      {fmt};"]
    if fmt == "binary":
        lines.append('    arch        "LSB;label=64;scalar=64";')
    lines.append(f"    class       {cls};")
    if location:
        lines.append(f'    location    "{location}";')
    lines += [f"    object      {name};", "}", "// " + "* " * 37 + "//", "", ""]
    return "\n".join(lines)


def write_field(
    path: str | Path,
    array: np.ndarray,
    *,
    fmt: str = "binary",
    precision: int = 6,
    location: str = "",
    name: str | None = None,
) -> None:
    """Write one particle field to ``path`` (class chosen from dtype/shape).

    ``fmt`` is ``"binary"`` (bit-exact) or ``"ascii"`` (floats written with
    ``precision`` significant digits; 17 is bit-exact).
    """
    if fmt not in ("binary", "ascii"):
        raise ValueError(f"fmt must be 'binary' or 'ascii', not {fmt!r}")
    path = Path(path)
    cls, a = _class_of(np.asarray(array))
    n = len(a)
    head = _header(cls, fmt, location, name or path.name).encode()
    if fmt == "binary":
        body = b"%d\n(" % n + a.tobytes() + b")\n;\n"
    elif n == 0:
        body = b"0\n(\n)\n;\n"
    else:
        if cls == "labelField":
            item = "%d\n"
        elif cls == "scalarField":
            item = f"%.{precision}g\n"
        else:
            item = f"(%.{precision}g %.{precision}g)\n"
        body = (f"{n}\n(\n" + (item * n) % tuple(a.ravel().tolist()) + ")\n;\n").encode()
    path.write_bytes(head + body)


# ----------------------------------------------------------------------------- cloud format
def _pad_z(a: np.ndarray) -> np.ndarray:
    """Float (N, 2) or (N, 3) -> contiguous little-endian (N, 3) with z = 0 for 2-vectors."""
    a = np.asarray(a)
    if a.dtype.kind != "f" or a.ndim != 2 or a.shape[1] not in (2, 3):
        raise ValueError(f"expected float (N, 2) or (N, 3), got dtype {a.dtype}, shape {a.shape}")
    out = np.zeros((len(a), 3), dtype="<f8")
    out[:, : a.shape[1]] = a
    return out


def write_vectors(
    path: str | Path,
    array: np.ndarray,
    *,
    fmt: str = "binary",
    precision: int = 6,
    location: str = "",
    name: str | None = None,
) -> None:
    """Write (N, 2) or (N, 3) floats as an OpenFOAM ``vectorField`` (z = 0 for 2-vectors)."""
    if fmt not in ("binary", "ascii"):
        raise ValueError(f"fmt must be 'binary' or 'ascii', not {fmt!r}")
    path = Path(path)
    a = _pad_z(array)
    n = len(a)
    head = _header("vectorField", fmt, location, name or path.name).encode()
    if fmt == "binary":
        body = b"%d\n(" % n + a.tobytes() + b")\n;\n"
    else:
        item = f"(%.{precision}g %.{precision}g %.{precision}g)\n"
        body = (f"{n}\n(\n" + (item * n) % tuple(a.ravel().tolist()) + ")\n;\n").encode()
    path.write_bytes(head + body)


def _positions_record(scalar: np.dtype, label: np.dtype) -> np.dtype:
    """One binary ``positions`` line: ``(``, x y z, the cell index, ``)`` and a newline."""
    return np.dtype([("open", "S1"), ("x", scalar, (3,)), ("celli", label), ("close", "S2")])


def write_positions(
    path: str | Path,
    positions: np.ndarray,
    *,
    fmt: str = "binary",
    precision: int = 6,
    location: str = "",
    cell: np.ndarray | int = 0,
) -> None:
    """Write particle positions as OpenFOAM's ``Cloud<passiveParticle>`` ``positions`` file.

    Each particle is ``(x y z) celli`` (z = 0 for (N, 2) input; ``cell`` is the index of
    the mesh cell holding it, 0 for the one-cell mesh of ``constant/polyMesh``). In
    binary each record is ``(`` + 3 scalars + 1 label + ``)``, as OpenFOAM writes a
    particle's raw bytes.
    """
    if fmt not in ("binary", "ascii"):
        raise ValueError(f"fmt must be 'binary' or 'ascii', not {fmt!r}")
    path = Path(path)
    xyz = _pad_z(positions)
    n = len(xyz)
    celli = np.broadcast_to(np.asarray(cell, dtype="<i8"), (n,))
    head = _header(POSITIONS_CLASS, fmt, location, "positions").encode()
    if fmt == "binary":
        rec = np.empty(n, dtype=_positions_record(np.dtype("<f8"), np.dtype("<i8")))
        rec["open"], rec["x"], rec["celli"], rec["close"] = b"(", xyz, celli, b")\n"
        body = b"%d\n(\n" % n + rec.tobytes() + b")\n;\n"
    else:
        item = f"(%.{precision}g %.{precision}g %.{precision}g) %d\n"
        vals = np.column_stack([xyz, celli]).ravel().tolist()  # %d formats the cell index
        body = (f"{n}\n(\n" + (item * n) % tuple(vals) + ")\n;\n").encode()
    path.write_bytes(head + body)


def _read_positions(buf: bytes, header: dict[str, str], i: int, path: Path) -> np.ndarray:
    """(N, 3) float64 points of a ``Cloud<...>`` positions file (cell indices dropped)."""
    i = _skip(buf, i)
    m = _INT.match(buf, i)
    if m is None:
        raise ValueError(f"{path}: expected the number of particles after the header")
    n = int(m[0])
    i = _skip(buf, m.end())
    if buf[i : i + 1] != b"(":
        raise ValueError(f"{path}: expected '(' after the number of particles {n}")
    i += 1
    if header.get("format", "ascii") == "binary":
        sdt, ldt = _binary_dtypes(header.get("arch", ""))
        rec = _positions_record(sdt, ldt)
        i = _skip(buf, i)
        if len(buf) < i + n * rec.itemsize:
            raise ValueError(f"{path}: truncated binary positions (expected {n} particles)")
        recs = np.frombuffer(buf, dtype=rec, count=n, offset=i)
        if n and not ((recs["open"] == b"(").all() and (recs["close"] == b")\n").all()):
            raise ValueError(f"{path}: malformed binary positions: expected one "
                             "'(' x y z celli ')' record per line")
        return recs["x"].astype(np.float64)
    end = buf.rfind(b")")
    if end < i:
        raise ValueError(f"{path}: unterminated list")
    tokens = buf[i:end].translate(_PARENS).split()
    if len(tokens) != 4 * n:
        raise ValueError(f"{path}: expected {n} records '(x y z) celli', found {len(tokens) / 4:g}")
    return np.array(tokens, dtype=np.float64).reshape(n, 4)[:, :3].copy()


# ----------------------------------------------------------------------------- reading
def _skip(buf: bytes, i: int) -> int:
    """Index of the first byte at/after ``i`` that is not whitespace or comment."""
    return _WS_COMMENT.match(buf, i).end()


def _parse_header(buf: bytes, path: Path) -> tuple[dict[str, str], int]:
    i = _skip(buf, 0)
    if not buf.startswith(b"FoamFile", i):
        raise ValueError(f"{path}: missing FoamFile header")
    i = _skip(buf, i + 8)
    if buf[i : i + 1] != b"{":
        raise ValueError(f"{path}: malformed FoamFile header")
    header, i = {}, i + 1
    while True:
        i = _skip(buf, i)
        if buf[i : i + 1] == b"}":
            return header, i + 1
        m = _ENTRY.match(buf, i)
        if m is None:
            raise ValueError(f"{path}: malformed FoamFile header near byte {i}")
        try:
            header[m[1].decode()] = m[2].decode().strip().strip('"')
        except UnicodeDecodeError:
            raise ValueError(f"{path}: FoamFile header is not UTF-8 text (near byte {i})") from None
        i = m.end()


def _binary_dtypes(arch: str) -> tuple[np.dtype, np.dtype]:
    """(scalar, label) dtypes described by an ``arch`` header entry."""
    order = ">" if "MSB" in arch else "<"
    lab = re.search(r"label=(\d+)", arch)
    sca = re.search(r"scalar=(\d+)", arch)
    lbits = int(lab[1]) if lab else 64
    sbits = int(sca[1]) if sca else 64
    return np.dtype(f"{order}f{sbits // 8}"), np.dtype(f"{order}i{lbits // 8}")


def read_field(path: str | Path) -> np.ndarray:
    """Read one particle field written by :func:`write_field` (or OpenFOAM).

    Returns float64 ``(N,)``/``(N, 2)``/``(N, 3)`` or int64 ``(N,)`` arrays.
    """
    path = Path(path)
    buf = path.read_bytes()
    header, i = _parse_header(buf, path)
    cls = header.get("class")
    if cls is not None and cls.startswith("Cloud<"):  # a cloud's positions file
        return _read_positions(buf, header, i, path)
    if cls not in _CLASSES:
        raise ValueError(f"{path}: unsupported field class {cls!r}")
    kind, ncomp = _CLASSES[cls]
    out_dtype = np.int64 if kind == "label" else np.float64
    shape = (-1, ncomp) if ncomp > 1 else (-1,)

    i = _skip(buf, i)
    m = _INT.match(buf, i)
    if m is None:
        raise ValueError(f"{path}: expected list size after header")
    n = int(m[0])
    i = _skip(buf, m.end())
    opener = buf[i : i + 1]

    if opener == b"{":  # uniform list: N{value}
        end = buf.index(b"}", i)
        vals = np.array(buf[i + 1 : end].translate(_PARENS).split(), dtype=out_dtype)
        if vals.size != ncomp:
            raise ValueError(f"{path}: bad uniform value")
        return np.tile(vals, (n, 1)).reshape(shape)
    if opener != b"(":
        raise ValueError(f"{path}: expected '(' after list size {n}")

    if header.get("format", "ascii") == "binary":
        sdt, ldt = _binary_dtypes(header.get("arch", ""))
        dt = ldt if kind == "label" else sdt
        nbytes = n * ncomp * dt.itemsize
        end = i + 1 + nbytes
        if len(buf) < end or buf[_skip(buf, end) : _skip(buf, end) + 1] != b")":
            raise ValueError(f"{path}: truncated binary list (expected {n} items)")
        data = np.frombuffer(buf, dtype=dt, count=n * ncomp, offset=i + 1)
        return data.astype(out_dtype).reshape(shape)  # astype copies: writable

    end = buf.rfind(b")")
    if end <= i:
        raise ValueError(f"{path}: unterminated list")
    tokens = buf[i + 1 : end].translate(_PARENS).split()
    if len(tokens) != n * ncomp:
        raise ValueError(f"{path}: expected {n * ncomp} values, found {len(tokens)}")
    if kind == "label":
        return np.array(tokens, dtype=np.int64)
    return np.array(tokens, dtype=np.float64).reshape(shape)


# ----------------------------------------------------------------------------- states
def write_state(
    time_dir: str | Path,
    fields: dict[str, np.ndarray],
    *,
    fmt: str = "binary",
    precision: int = 6,
) -> None:
    """Write every field to ``time_dir/lagrangian/particles/<name>``, atomically.

    ``positions`` goes to OpenFOAM's cloud format (:func:`write_positions`), float
    (N, 2) arrays to 3-component ``vectorField`` files with z = 0 (:func:`write_vectors`),
    everything else through :func:`write_field`.
    """
    time_dir = Path(time_dir)
    cloud = time_dir / CLOUD_DIR
    cloud.mkdir(parents=True, exist_ok=True)
    location = f"{time_dir.name}/{CLOUD_DIR.as_posix()}"
    for name, arr in fields.items():
        tmp = cloud / f".{name}.{os.getpid()}.{threading.get_ident()}.tmp"
        a = np.asarray(arr)
        try:
            if name == "positions":
                write_positions(tmp, a, fmt=fmt, precision=precision, location=location)
            elif a.ndim == 2 and a.shape[1] in (2, 3) and a.dtype.kind == "f":
                write_vectors(tmp, a, fmt=fmt, precision=precision, location=location, name=name)
            else:
                write_field(tmp, a, fmt=fmt, precision=precision, location=location, name=name)
            os.replace(tmp, cloud / name)
        except BaseException:
            tmp.unlink(missing_ok=True)
            raise


def _field_files(cloud: Path) -> list[Path]:
    return sorted(
        p
        for p in cloud.iterdir()
        if p.is_file() and not p.name.startswith(".") and not p.name.endswith((".tmp", "~"))
    )


def _in_plane(a: np.ndarray) -> np.ndarray:
    """A 2-D case's 3-vectors (z = 0 everywhere) as (N, 2); anything else unchanged."""
    if a.ndim == 2 and a.shape[1] == 3 and not a[:, 2].any():
        return np.ascontiguousarray(a[:, :2])
    return a


def read_state(time_dir: str | Path, dim: int | None = None) -> dict[str, np.ndarray]:
    """Read every particle field of a time directory into ``{name: array}``.

    A 2-D case's positions and vectors come back as in-plane (N, 2) arrays whether they
    were written as 3-vectors with z = 0 (the OpenFOAM layout) or as ``vector2DField``
    (cases written by earlier sphfoam versions); a 3-D case's as (N, 3). ``dim`` (the
    case's ``dimension``) decides; without it, positions with any z != 0 are 3-D.
    """
    cloud = Path(time_dir) / CLOUD_DIR
    if not cloud.is_dir():
        raise FileNotFoundError(f"no particle data: directory {cloud} does not exist")
    raw = {p.name: read_field(p) for p in _field_files(cloud)}
    pos = raw.get("positions")
    if dim is None:
        dim = 3 if pos is not None and pos.ndim == 2 and pos.shape[1] == 3 \
            and pos[:, 2].any() else 2
    if dim == 3:
        return raw
    return {k: _in_plane(a) for k, a in raw.items()}


def field_header(path: str | Path) -> dict[str, str]:
    """The ``FoamFile`` header entries of a field file (class, format, arch, ...)."""
    path = Path(path)
    with path.open("rb") as fh:
        buf = fh.read(4096)
    return _parse_header(buf, path)[0]


def upgrade_state(time_dir: str | Path) -> bool:
    """Rewrite a time directory of an earlier sphfoam (``vector2DField`` positions and
    vectors) in the cloud layout of :func:`write_state`, values unchanged bit for bit
    (binary stays binary; ascii is rewritten with 17 digits). True if it was rewritten."""
    cloud = Path(time_dir) / CLOUD_DIR
    files = _field_files(cloud) if cloud.is_dir() else []
    headers = {p.name: field_header(p) for p in files}
    old = [n for n, h in headers.items()
           if h.get("class") == "vector2DField" or (n == "positions"
                                                    and not h.get("class", "").startswith("Cloud<"))]
    if not old:
        return False
    fmt = headers[old[0]].get("format", "ascii")
    state = read_state(time_dir)
    write_state(time_dir, {n: state[n] for n in old}, fmt=fmt, precision=17)
    return True


def has_particles(time_dir: str | Path) -> bool:
    """True if ``time_dir`` holds at least one particle field file."""
    cloud = Path(time_dir) / CLOUD_DIR
    return cloud.is_dir() and bool(_field_files(cloud))
