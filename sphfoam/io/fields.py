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
"""

from __future__ import annotations

import os
import re
import threading
from pathlib import Path

import numpy as np

__all__ = ["write_field", "read_field", "write_state", "read_state", "has_particles", "CLOUD_DIR"]

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
    """Write every field to ``time_dir/lagrangian/particles/<name>``, atomically."""
    time_dir = Path(time_dir)
    cloud = time_dir / CLOUD_DIR
    cloud.mkdir(parents=True, exist_ok=True)
    location = f"{time_dir.name}/{CLOUD_DIR.as_posix()}"
    for name, arr in fields.items():
        tmp = cloud / f".{name}.{os.getpid()}.{threading.get_ident()}.tmp"
        try:
            write_field(tmp, arr, fmt=fmt, precision=precision, location=location, name=name)
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


def read_state(time_dir: str | Path) -> dict[str, np.ndarray]:
    """Read every particle field of a time directory into ``{name: array}``."""
    cloud = Path(time_dir) / CLOUD_DIR
    if not cloud.is_dir():
        raise FileNotFoundError(f"no particle data: directory {cloud} does not exist")
    return {p.name: read_field(p) for p in _field_files(cloud)}


def has_particles(time_dir: str | Path) -> bool:
    """True if ``time_dir`` holds at least one particle field file."""
    cloud = Path(time_dir) / CLOUD_DIR
    return cloud.is_dir() and bool(_field_files(cloud))
