"""Reader and writer for OpenFOAM dictionary files, reading OpenFOAM's syntax as
OpenFOAM reads it.

The reader runs in linear time: one compiled regular expression splits the
text into tokens in a single pass, and a recursive-descent parser walks the
token list with an index. Line and column numbers are only worked out when an
error is reported. Long ``List<T>`` bodies skip the tokenizer and are read by one
compiled pass straight into a numpy array (:mod:`sphfoam.case.asciinum`).

Grammar
-------
::

    file       := entry*
    entry      := key '{' entry* '}' [';']      sub-dictionary
                | key item* ';'                 key value;  (no items -> None)
                | '$' name ';'                  merge a dictionary macro here
                | directive
                | ';'                           stray ';' (e.g. after '}'), skipped
    key        := word | number | "quoted"      (the token's text is the key;
                                                 a quoted key is a regular expression)
    item       := number | word | "quoted" | '$' name
                | [count] '(' (item | '{' entry* '}')* ')'  list
                | count '{' item '}'            uniform list
                | '[' number* ']'               dimension set
                | '[' units ']'                 dimension set in units: [m/s], [kg m^-3]
    directive  := '#include' "file" | '#includeIfPresent' "file"
                | '#remove' key | '#remove' '(' key* ')' | '#inputMode' word
                | '#inputSyntax' ('slash' | 'dot')

Words are as in OpenFOAM: anything up to whitespace or one of ``;{}[]"``, and a word
that does not start like a number also takes *balanced* parentheses with no space
inside, so ``div(phi,U) Gauss linearUpwind grad(U);`` is the key ``div(phi,U)`` with
the value ``("Gauss", "linearUpwind", "grad(U)")``, and ``CH2(S)`` is one word. A word
with a ``(`` left open before a space (``uniform(0 0 0)``) is an error.

A ``count`` is a non-negative integer directly followed by ``(`` or ``{``
(``3(1 2 3)``, ``4{0.5}``) or followed by ``(`` on a later line (as OpenFOAM
writes long lists: ``3`` newline ``(`` ...). The number of items must match.
An integer followed by ``(`` on the same line after a space is an ordinary
item, so ``arc 1 2 (0 1 0)`` reads as ``['arc', 1, 2, [0, 1, 0]]``.

Comments (``// ...`` to end of line and ``/* ... */``) may appear between
any two tokens. ``FoamFile { ... }`` is kept as an ordinary sub-dictionary.

How values come back from :func:`parse`:

* one item -> the item itself, several items -> a ``tuple`` of the items,
  no items (``key;``) -> ``None``;
* ``3``, ``-2`` -> ``int``; ``1e-3``, ``0.5``, ``-1.``, ``.5`` -> ``float``;
* other bare words (``on``, ``uniform``, ``a.b``, ``List<scalar>``) -> ``str``,
  never converted to bool; ``"text"`` -> :class:`QuotedString` (only ``\\"``
  and ``\\\\`` are unescaped, other backslashes are kept as written);
* ``( ... )`` -> ``list`` (a ``{ ... }`` inside a list is a ``dict`` item);
  ``[ ... ]`` -> :class:`DimensionSet`; ``key { ... }`` -> ``dict``;
* a counted ``List<scalar>``, ``List<label>``, ``List<vector>``, ``List<vector2D>``,
  ``List<tensor>`` or ``List<symmTensor>`` of at least
  :data:`ARRAY_MIN_ITEMS` numbers -> a float64 (int64 for labels) numpy array of shape
  ``(N,)`` or ``(N, components)``, bit for bit ``float(token)`` of every token;
  shorter lists, and lists that are not plain numbers, come back as lists.

Dimension sets are seven (or five) numbers, or an expression in units and named
dimensions: ``[m/s]``, ``[kg m^-3]``, ``[m^2/s]``, ``[(mol/cm^3)^-0.5/s]``,
``[velocity]`` (see :data:`UNITS` and :data:`DIMENSIONS`; juxtaposition and ``*``
multiply, ``/`` divides left to right, ``^`` raises to a number). The
:class:`DimensionSet` holds the exponents, the unit text and the unit's SI ``factor``
(``[g/cm^3]``: 1000), which the case schemas apply to the value. A dimension set
followed by a word on a new line (a missing ``;``) is an error on that line.

Entries keep file order. A later scalar entry replaces an earlier one with the
same key; a later sub-dictionary is merged recursively into an earlier one.
``#include`` paths are relative to the directory of the file that includes
them, and the included entries are merged into the current dictionary.

Keys: a quoted key (``"(U|k|epsilon)"``) is a regular expression. Lookups through
:func:`lookup` and ``$`` references follow OpenFOAM's order: the exact key first,
then the quoted keys matching the whole name, the last defined first. ``#remove
"U.*"`` removes the matching keys.

Macros: ``$x`` or ``${x}`` is replaced by a deep copy of ``x``, looked up in
the current dictionary (as parsed so far) and then in the enclosing ones.
Two scoping syntaxes are read (OpenFOAM's ``#inputSyntax``; by default a name with a
``/`` or ``!`` is slash syntax, any other dot syntax):

* dot: ``$a.b.c`` looks up ``a`` that way and then goes down through ``b`` and ``c``
  (keys may contain dots: ``$dotted.k.l`` finds ``dotted { "k.l" ...}``); ``$:a.b``
  starts at the top level; leading dots choose where the search starts: ``$.x`` in the
  current dictionary, ``$..x`` in its parent, and each extra dot one level further up;
* slash: ``$a/b`` goes down from ``a``; each leading ``../`` goes up one level
  (``$../../a/b``); ``$!a/b`` starts at the top level; ``$file!a/b`` looks ``a/b`` up
  in another dictionary file (a path as for ``#include``). With ``#inputSyntax
  slash;`` dots are only part of keys (``$U.air`` is the key ``U.air``).

A multi-token macro value is spliced into the surrounding items. A standalone
``$dict;`` entry merges the entries of ``dict`` into the current dictionary.
``$FOAM_CASE`` and ``$FOAM_CASENAME``, when no entry has that name, are the case
directory and its name (as OpenFOAM falls back to the environment).

Paths (``#include``, ``$file!...``): ``$FOAM_CASE``, ``$FOAM_CASENAME``, ``${...}``
and OpenFOAM's ``<case>``, ``<system>``, ``<constant>`` are expanded (:func:`expand`;
no other environment variable, no ``~``). A relative path must stay inside the case
directory (given to :func:`parse`/:func:`read`, else the nearest ancestor holding a
``system`` directory); an absolute path is taken as named, on purpose. Only regular
files up to :data:`MAX_FILE_BYTES` are read: directories, devices (``/dev/zero``),
FIFOs and ``/dev/stdin`` are refused before opening. Error messages about an included
file name the file and position but never quote its contents.

Refused with a clear error: code (``#calc``, ``#codeStream``, ``#eval``, verbatim
``#{ ... #}``: sphfoam never compiles or executes code from a dictionary), binary files
(NUL bytes, or a ``format binary`` header over list data), bytes that are not UTF-8
(the error names the file, line and column), and the directives sphfoam does not read
(``#includeEtc``, ``#includeFunc``, ...). Not supported: ``$macro`` as a key, and files
whose top level is a bare list (polyMesh files).

:func:`dumps` writes text that :func:`parse` reads back equal, with the same
types. It raises ``ValueError`` for values that have no exact text form: a
``str`` that is not a valid bare word (use :class:`QuotedString`), non-finite
floats, tuples with fewer than two items, tuples inside tuples or lists, and
``None`` or ``dict`` inside a tuple. ``True``/``False`` are written as the
words ``true``/``false``. A dimension set read in units is written in those units.
"""

from __future__ import annotations

import functools
import math
import numbers
import os
import re
import stat
from pathlib import Path

import numpy as np

__all__ = ["FoamDictError", "QuotedString", "DimensionSet", "parse", "read", "dumps", "write",
           "lookup", "expand", "read_text", "decode", "UNITS", "DIMENSIONS"]

#: Largest file ``read``, ``#include`` or a ``$file!entry`` reference will read, in bytes.
MAX_FILE_BYTES = 64 * 1024 * 1024
#: Counted ``List<T>`` lists with at least this many items come back as numpy arrays.
ARRAY_MIN_ITEMS = 100


class FoamDictError(ValueError):
    """Syntax error in a dictionary file, with the position it was found at."""

    def __init__(self, message: str, filename: str | None = None,
                 line: int | None = None, column: int | None = None):
        super().__init__(message, filename, line, column)
        self.message, self.filename, self.line, self.column = message, filename, line, column

    def __str__(self) -> str:
        where = [str(x) for x in (self.filename, self.line, self.column) if x is not None]
        return ":".join([*where, " " + self.message]) if where else self.message


class QuotedString(str):
    """A string that was (and will be written) in double quotes.

    As a dictionary key it is a regular expression (OpenFOAM's ``"(U|k|epsilon)"``
    keys): :func:`lookup` and ``$`` references try exact keys first, then the quoted
    keys as whole-key regular expressions, the last one defined first."""

    __slots__ = ()

    def __repr__(self) -> str:
        return f"QuotedString({str.__repr__(self)})"


class DimensionSet(tuple):
    """A dimension set: exponents of (mass, length, time, temperature, moles, current,
    luminous intensity), read from ``[0 1 -1 0 0 0 0]`` or from units/named dimensions
    (``[m/s]``, ``[kg m^-3]``, ``[velocity]``).

    ``units`` is the unit text as written (``None`` for the numeric form) and ``factor``
    the SI value of one such unit (``[mm]`` has factor 1e-3): a value given in these units
    is ``factor`` times its SI value. Equality compares the exponents only."""

    def __new__(cls, exponents=(), units: str | None = None, factor: float = 1.0):
        self = super().__new__(cls, exponents)
        self.units, self.factor = units, factor
        return self

    def __reduce__(self):
        return (DimensionSet, (tuple(self), self.units, self.factor))

    def __repr__(self) -> str:
        if self.units is None:
            return f"DimensionSet({tuple.__repr__(self)})"
        return f"DimensionSet({tuple.__repr__(self)}, units={self.units!r}, factor={self.factor!r})"


# ----------------------------------------------------------------------------
# Units (OpenFOAM's SI unit set and named dimensions)
# ----------------------------------------------------------------------------

def _dims(M=0, L=0, T=0, Th=0, N=0, I=0, J=0):
    return (M, L, T, Th, N, I, J)


#: Named dimensions accepted in a dimension set, e.g. ``[velocity]`` (factor 1).
DIMENSIONS = {
    "dimless": _dims(), "dimensionless": _dims(), "none": _dims(),
    "mass": _dims(M=1), "length": _dims(L=1), "time": _dims(T=1), "temperature": _dims(Th=1),
    "moles": _dims(N=1), "current": _dims(I=1), "luminousIntensity": _dims(J=1),
    "area": _dims(L=2), "volume": _dims(L=3), "velocity": _dims(L=1, T=-1),
    "acceleration": _dims(L=1, T=-2), "density": _dims(M=1, L=-3),
    "momentum": _dims(M=1, L=1, T=-1), "force": _dims(M=1, L=1, T=-2),
    "energy": _dims(M=1, L=2, T=-2), "power": _dims(M=1, L=2, T=-3),
    "pressure": _dims(M=1, L=-1, T=-2), "kinematicPressure": _dims(L=2, T=-2),
    "compressibility": _dims(L=-2, T=2), "viscosity": _dims(L=2, T=-1),
    "kinematicViscosity": _dims(L=2, T=-1), "dynamicViscosity": _dims(M=1, L=-1, T=-1),
    "flux": _dims(L=3, T=-1), "volumetricFlux": _dims(L=3, T=-1), "massFlux": _dims(M=1, T=-1),
    "rate": _dims(T=-1), "frequency": _dims(T=-1),
    "specificHeatCapacity": _dims(L=2, T=-2, Th=-1), "gasConstant": _dims(L=2, T=-2, Th=-1),
}

#: Units accepted in a dimension set: name -> (exponents, SI value of one unit).
UNITS = {
    "kg": (_dims(M=1), 1.0), "g": (_dims(M=1), 1e-3), "t": (_dims(M=1), 1e3),
    "m": (_dims(L=1), 1.0), "km": (_dims(L=1), 1e3), "cm": (_dims(L=1), 1e-2),
    "mm": (_dims(L=1), 1e-3), "um": (_dims(L=1), 1e-6), "nm": (_dims(L=1), 1e-9),
    "s": (_dims(T=1), 1.0), "ms": (_dims(T=1), 1e-3), "us": (_dims(T=1), 1e-6),
    "min": (_dims(T=1), 60.0), "hr": (_dims(T=1), 3600.0), "day": (_dims(T=1), 86400.0),
    "K": (_dims(Th=1), 1.0), "mol": (_dims(N=1), 1.0), "kmol": (_dims(N=1), 1e3),
    "A": (_dims(I=1), 1.0), "cd": (_dims(J=1), 1.0), "Cd": (_dims(J=1), 1.0),
    "N": (_dims(M=1, L=1, T=-2), 1.0), "kN": (_dims(M=1, L=1, T=-2), 1e3),
    "Pa": (_dims(M=1, L=-1, T=-2), 1.0), "kPa": (_dims(M=1, L=-1, T=-2), 1e3),
    "MPa": (_dims(M=1, L=-1, T=-2), 1e6), "bar": (_dims(M=1, L=-1, T=-2), 1e5),
    "atm": (_dims(M=1, L=-1, T=-2), 101325.0),
    "J": (_dims(M=1, L=2, T=-2), 1.0), "kJ": (_dims(M=1, L=2, T=-2), 1e3),
    "W": (_dims(M=1, L=2, T=-3), 1.0), "kW": (_dims(M=1, L=2, T=-3), 1e3),
    "Hz": (_dims(T=-1), 1.0), "l": (_dims(L=3), 1e-3), "L": (_dims(L=3), 1e-3),
    "rad": (_dims(), 1.0), "deg": (_dims(), math.pi / 180), "rpm": (_dims(T=-1), math.pi / 30),
    "%": (_dims(), 1e-2),
}

_UNIT_TOKEN_RE = re.compile(
    r"\s*(?:(?P<num>[+-]?(?:[0-9]+\.?[0-9]*|\.[0-9]+)(?:[eE][+-]?[0-9]+)?)"
    r"|(?P<name>[A-Za-z_%][A-Za-z_0-9]*)|(?P<op>[*/^()])|(?P<bad>\S))")
_COMMENTS_RE = re.compile(r"//[^\n]*|/\*.*?\*/", re.S)


def _units(text: str):
    """(exponents, factor) of a unit expression such as ``kg m^-3``, ``m/s``,
    ``(mol/cm^3)^-0.5/s`` or ``velocity``. Juxtaposition and ``*`` multiply, ``/``
    divides (left to right, equal precedence), ``^`` raises to a number."""
    toks = [(m.lastgroup, m.group(m.lastgroup)) for m in _UNIT_TOKEN_RE.finditer(text)
            if m.lastgroup]
    pos = 0

    def fail(msg):
        raise ValueError(msg)

    def atom():
        nonlocal pos
        if pos >= len(toks):
            fail("unit expression ends too early")
        kind, s = toks[pos]
        pos += 1
        if kind == "name":
            if s in DIMENSIONS:
                return [float(x) for x in DIMENSIONS[s]], 1.0
            if s in UNITS:
                return [float(x) for x in UNITS[s][0]], UNITS[s][1]
            fail(f"unknown unit {s!r}")
        if kind == "op" and s == "(":
            v = expr()
            if pos >= len(toks) or toks[pos] != ("op", ")"):
                fail("missing ')' in unit expression")
            pos += 1
            return v
        fail(f"unexpected {s!r} in unit expression")

    def power():
        nonlocal pos
        exps, factor = atom()
        if pos < len(toks) and toks[pos] == ("op", "^"):
            pos += 1
            if pos >= len(toks) or toks[pos][0] != "num":
                fail("'^' must be followed by a number")
            p = float(toks[pos][1])
            pos += 1
            exps, factor = [e * p for e in exps], factor ** p
        return exps, factor

    def expr():
        nonlocal pos
        exps, factor = power()
        while pos < len(toks) and toks[pos] != ("op", ")"):
            div = toks[pos] == ("op", "/")
            if toks[pos] in (("op", "/"), ("op", "*")):
                pos += 1
            e2, f2 = power()
            if div:
                exps, factor = [a - b for a, b in zip(exps, e2)], factor / f2
            else:
                exps, factor = [a + b for a, b in zip(exps, e2)], factor * f2
        return exps, factor

    if not toks:
        fail("empty unit expression")
    exps, factor = expr()
    if pos != len(toks):
        fail(f"unexpected {toks[pos][1]!r} in unit expression")
    return tuple(int(e) if e == int(e) else e for e in exps), factor


# ----------------------------------------------------------------------------
# Text and files
# ----------------------------------------------------------------------------

_FORMAT_BINARY_RE = re.compile(r"FoamFile\s*\{[^}]*\bformat\s+binary\s*;", re.S)


def read_text(path, filename: str | None = None) -> str:
    """Text of a dictionary file, refusing what is not one.

    Raises :class:`FoamDictError` (naming ``filename``, by default ``path``) for a
    directory, a device, FIFO or socket (``/dev/zero``, ``/dev/stdin``), a file over
    :data:`MAX_FILE_BYTES`, binary content (NUL bytes, or a ``format binary`` header
    over counted lists) and bytes that are not UTF-8 (a latin-1 ``é``)."""
    path = Path(path)
    name = str(path) if filename is None else filename
    try:
        st = os.stat(path)
    except OSError as exc:
        raise FoamDictError(f"cannot read file: {exc.strerror}", name) from None
    except ValueError:  # a NUL character in the path
        raise FoamDictError("the file name contains a NUL character", name) from None
    if stat.S_ISDIR(st.st_mode):
        raise FoamDictError("is a directory, not a dictionary file", name)
    if not stat.S_ISREG(st.st_mode):
        raise FoamDictError("is not a regular file (a device, FIFO or socket); sphfoam reads "
                            "dictionaries only from regular files", name)
    if st.st_size > MAX_FILE_BYTES:
        raise FoamDictError(f"file is {st.st_size} bytes; dictionary files are limited to "
                            f"{MAX_FILE_BYTES // 2**20} MiB", name)
    try:
        with open(path, "rb") as fh:
            data = fh.read(MAX_FILE_BYTES + 1)
    except OSError as exc:
        raise FoamDictError(f"cannot read file: {exc.strerror}", name) from None
    if len(data) > MAX_FILE_BYTES:
        raise FoamDictError(f"file is larger than {MAX_FILE_BYTES // 2**20} MiB", name)
    return decode(data, name)


def decode(data: bytes, filename: str | None = None) -> str:
    """UTF-8 text of ``data``, or a :class:`FoamDictError` for binary or non-UTF-8 bytes."""
    nul = data.find(b"\0")
    if nul >= 0:
        raise FoamDictError(
            f"binary file (NUL byte at offset {nul}): sphfoam reads dictionaries as text; "
            "particle fields in binary format are read by sphfoam.io.fields", filename)
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError as exc:
        line = data.count(b"\n", 0, exc.start) + 1
        col = exc.start - (data.rfind(b"\n", 0, exc.start) + 1) + 1
        raise FoamDictError(f"byte 0x{data[exc.start]:02x} is not UTF-8 text "
                            "(binary data, or a file saved as latin-1: save it as UTF-8)",
                            filename, line, col) from None
    m = _FORMAT_BINARY_RE.search(text, 0, 4096)
    if m and re.search(r"[0-9]\s*\(", text[m.end():]):
        raise FoamDictError("'format binary' file with list data: the dictionary reader reads "
                            "ascii only (particle fields are read by sphfoam.io.fields)",
                            filename)
    return text


_CASE_VAR_RE = re.compile(
    r"\$\{(FOAM_CASE(?:NAME)?)\}|\$(FOAM_CASE(?:NAME)?)(?![A-Za-z0-9_])|<(case|system|constant)>")


def expand(text: str, case_dir) -> str:
    """``text`` with ``$FOAM_CASE``, ``$FOAM_CASENAME`` (also ``${...}``) and OpenFOAM's
    ``<case>``, ``<system>``, ``<constant>`` replaced for the case ``case_dir``.

    Raises ``ValueError`` when ``case_dir`` is ``None`` and a variable is used."""

    def sub(m):
        var = m.group(1) or m.group(2)
        if case_dir is None:
            raise ValueError(f"{m.group(0)} is used but the case directory is not known")
        root = Path(case_dir)
        if var == "FOAM_CASENAME":
            return root.resolve().name
        if var == "FOAM_CASE" or m.group(3) == "case":
            return str(root)
        return str(root / m.group(3))

    return _CASE_VAR_RE.sub(sub, text)


def _find_case(start: Path) -> Path | None:
    """The case directory holding ``start``: the nearest ancestor with a ``system``
    directory."""
    try:
        start = start.resolve()
    except OSError:
        return None
    for d in (start, *start.parents):
        if (d / "system").is_dir():
            return d
    return None


# ----------------------------------------------------------------------------
# Tokenizer
# ----------------------------------------------------------------------------

# A word: no whitespace, no ';(){}[]"', not starting with '$' or '#', and no
# '//' or '/*' inside (those start comments). As in OpenFOAM, a word that does not
# start like a number also takes balanced parentheses with no whitespace inside:
# ``div(phi,U)``, ``grad(U)``, ``CH2(S)``, ``div((nuEff*dev2(T(grad(U)))))``.
_WCH = r'(?:[^\s;(){}\[\]"/]|/(?![/*]))'
_PAREN_DEPTH = 10


def _word_pattern() -> str:
    inner = _WCH
    for _ in range(_PAREN_DEPTH):
        inner = r'(?:' + _WCH + r'|\(' + inner + r'*\))'
    start = r'(?:[^\s;(){}\[\]"/$#0-9+\-.]|/(?![/*]))'
    numlike = r'[0-9+\-.]' + _WCH + '*'
    return r'(?:' + start + inner + r'*|' + numlike + r')'


_WORD = _word_pattern()
_TOKEN_RE = re.compile(
    r'\s*(?:'
    r'(?P<comment>//[^\n]*|/\*.*?\*/)'
    r'|(?P<opencomment>/\*)'
    r'|(?P<str>"(?:[^"\\]|\\.)*")'
    r'|(?P<openstr>")'
    r'|(?P<punct>[;(){}\[\]])'
    r'|(?P<verbatim>#\{)'
    r'|(?P<dir>#[A-Za-z]\w*)'
    r'|(?P<macro>\$(?:\{[^{}\s]*\}|(?:[^\s;(){}\[\]"$#/]|/(?![/*]))+))'
    r'|(?P<word>' + _WORD + r')'
    r'|(?P<bad>\S)'
    r')', re.S)
_WORD_RE = re.compile(_WORD)
_INT_RE = re.compile(r'[+-]?[0-9]+')
_FLOAT_RE = re.compile(r'[+-]?(?:[0-9]+\.[0-9]*|\.[0-9]+|[0-9]+)(?:[eE][+-]?[0-9]+)?')
_UNESCAPE_RE = re.compile(r'\\([\\"])')
_NUMBER_START = frozenset("0123456789+-.")
_WS_RE = re.compile(r'\s*')

# Counted lists of a known element type, read straight into numpy arrays.
_LIST_TYPES = {"List<scalar>": ("f", 1), "List<label>": ("i", 1), "List<vector>": ("f", 3),
               "List<vector2D>": ("f", 2), "List<symmTensor>": ("f", 6),
               "List<tensor>": ("f", 9)}
# the count, then '(' right after it or on a later line (as the general reader's counts)
_LIST_HEAD_RE = re.compile(r'\s*([0-9]+)(?:\(|[ \t]*\n\s*\()')
_CLOSE2_RE = re.compile(r'\)\s*\)')

#: Directives that would compile or run code in OpenFOAM.
_CODE_DIRECTIVES = frozenset({"#calc", "#codeStream", "#eval", "#code", "#negate"})
_NEVER_CODE = ("sphfoam never compiles or executes code from a dictionary "
               "(#calc, #codeStream, #eval and #{ ... #} are refused); write the value itself")

# A token is (kind, value, position, text). Kinds: 'num', 'word', 'str',
# 'macro', 'dir', 'array', one of ';(){}[]' for punctuation, and 'eof'.


def _array(text: str, start: int, word: str):
    """A counted ``List<T>`` after ``word`` at ``start``, as (array, end) or None."""
    m = _LIST_HEAD_RE.match(text, start)
    if m is None:
        return None
    n = int(m.group(1))
    if n < ARRAY_MIN_ITEMS:
        return None
    kind, ncomp = _LIST_TYPES[word]
    body = m.end()
    # The list ends at the first ')' (scalars) or ')' ')' (tuples); parse_numbers checks
    # that everything before it is numbers, grouped in tuples of ncomp.
    if ncomp == 1:
        close = text.find(")", body)
    else:
        m = _CLOSE2_RE.search(text, body)
        close = m.end() - 1 if m else -1
    if close < 0:
        return None
    from sphfoam.case.asciinum import parse_numbers

    values = parse_numbers(text[body:close], n * ncomp, ncomp, integer=kind == "i")
    if values is None:
        return None  # not a plain number list: the general parser reads it (or says why)
    return values, close + 1


def _tokenize(text: str, error, show) -> list[tuple]:
    tokens: list[tuple] = []
    append = tokens.append
    match = _TOKEN_RE.match
    end, size = 0, len(text)
    while True:
        m = match(text, end)
        if m is None or m.lastgroup is None:
            break
        kind = m.lastgroup
        pos, end, s = m.start(kind), m.end(kind), m.group(kind)
        if kind == "word":
            if s[0] in _NUMBER_START:
                if _INT_RE.fullmatch(s):
                    append(("num", int(s), pos, s))
                    continue
                if _FLOAT_RE.fullmatch(s):
                    append(("num", float(s), pos, s))
                    continue
            elif end < size and text[end] == "(":
                raise error(f"word {show(s + '(')} has a '(' that is not closed before a space "
                            f"or ';' (or is nested more than {_PAREN_DEPTH} deep); OpenFOAM reads a "
                            "word up to the next space: put a space before a list", pos)
            append(("word", s, pos, s))
            if s in _LIST_TYPES:
                got = _array(text, end, s)
                if got is not None:
                    append(("array", got[0], end, "list"))
                    end = got[1]
        elif kind == "punct":
            append((s, s, pos, s))
        elif kind == "comment":
            pass
        elif kind == "str":
            append(("str", QuotedString(_UNESCAPE_RE.sub(r"\1", s[1:-1])), pos, s))
        elif kind in ("macro", "dir"):
            append((kind, s, pos, s))
        elif kind == "verbatim":
            raise error("verbatim code block '#{ ... #}': " + _NEVER_CODE, pos)
        elif kind == "opencomment":
            raise error("unterminated comment", pos)
        elif kind == "openstr":
            raise error("unterminated string", pos)
        else:
            raise error(f"unexpected character {show(s)}", pos)
    end = _WS_RE.match(text, end).end()
    append(("eof", None, end, "end of file"))
    return tokens


# ----------------------------------------------------------------------------
# Parser
# ----------------------------------------------------------------------------

_CLOSE_NAMES = {")": "list", "]": "dimension set", "}": "uniform list"}
_MAX_INCLUDE_DEPTH = 32
_MAX_NESTING = 200


def _copy(value):
    """Deep copy of a parsed value (containers only; scalars are immutable)."""
    if isinstance(value, dict):
        return {k: _copy(v) for k, v in value.items()}
    if isinstance(value, list):
        return [_copy(v) for v in value]
    if type(value) is tuple:
        return tuple(_copy(v) for v in value)
    if isinstance(value, np.ndarray):
        return value.copy()
    return value


def _assign(d: dict, key: str, value) -> None:
    """Set an entry: sub-dicts merge recursively, anything else replaces."""
    old = d.get(key)
    if isinstance(value, dict) and isinstance(old, dict):
        for k, v in value.items():
            _assign(old, k, v)
    else:
        d[key] = value


@functools.lru_cache(maxsize=1024)
def _regex(pattern: str):
    try:
        return re.compile(pattern)
    except re.error:
        return None


def _find(d: dict, key: str):
    """OpenFOAM's lookup order: the exact key, else the quoted (regular-expression) keys
    matching the whole of ``key``, the last defined first. Returns (found, value)."""
    if key in d:
        return True, d[key]
    for k in reversed(list(d)):
        if isinstance(k, QuotedString):
            rx = _regex(k)
            if rx is not None and rx.fullmatch(key):
                return True, d[k]
    return False, None


_MISSING = object()


def lookup(d: dict, key: str, default=_MISSING):
    """``d[key]`` as OpenFOAM looks it up: an exact key first, then quoted keys as
    regular expressions (``"(U|k|epsilon)"``) matching the whole key, the last defined
    first. Raises ``KeyError`` if nothing matches and no ``default`` is given."""
    found, value = _find(d, key)
    if found:
        return value
    if default is _MISSING:
        raise KeyError(key)
    return default


def _descend(d: dict, parts: list[str]):
    """Find ``parts`` (a dotted name split on '.') in ``d``; keys may contain dots."""
    for n in range(len(parts), 0, -1):
        found, value = _find(d, ".".join(parts[:n]))
        if found:
            if n == len(parts):
                return True, value
            if isinstance(value, dict):
                found, value = _descend(value, parts[n:])
                if found:
                    return True, value
    return False, None


def _walk(d: dict, parts: list[str]):
    """Find ``parts`` (a slash-scoped name split on '/') in ``d``."""
    value = d
    for p in parts:
        if not isinstance(value, dict):
            return False, None
        found, value = _find(value, p)
        if not found:
            return False, None
    return True, value


class _Parser:
    def __init__(self, text: str, filename: str | None, include_dir: Path, depth: int = 0,
                 case_dir: Path | None = None, syntax: str = "auto", nesting: int = 0):
        self.text, self.filename, self.include_dir, self.depth = text, filename, include_dir, depth
        self.case_dir, self.syntax = case_dir, syntax
        self.tokens = _tokenize(text, self.error, self.show)
        self.i = 0
        self.nesting = nesting

    def enter(self, pos) -> None:
        """Count one more level of nesting (lists, dictionaries) and refuse too many."""
        self.nesting += 1
        if self.nesting > _MAX_NESTING:
            raise self.error(f"lists or dictionaries nested more than {_MAX_NESTING} deep",
                             pos or 0)

    def show(self, s) -> str:
        """``repr(s)`` of text from the file, or a placeholder in an included file (whose
        contents are never echoed)."""
        return repr(str(s)) if self.depth == 0 else "(text of the included file not shown)"

    def plain(self, s) -> str:
        """``s`` as written, or the placeholder in an included file."""
        return str(s) if self.depth == 0 else "(text of the included file not shown)"

    def position(self, pos: int) -> tuple[int, int]:
        return self.text.count("\n", 0, pos) + 1, pos - self.text.rfind("\n", 0, pos)

    def error(self, message: str, pos: int) -> FoamDictError:
        return FoamDictError(message, self.filename, *self.position(pos))

    def parse_dict(self, d: dict, scopes: list[dict], open_pos: int | None = None) -> None:
        """Parse entries into ``d`` up to the matching '}' (or end of file if top level).

        ``scopes`` lists the dictionaries being built, outermost first, ``d`` last.
        """
        tokens = self.tokens
        self.enter(open_pos)
        while True:
            kind, value, pos, text = tokens[self.i]
            self.i += 1
            if kind in ("word", "num", "str"):
                key = value if kind == "str" else text
                if kind == "str" and _regex(key) is None:
                    raise self.error(f"key {self.show(text)} is not a valid regular expression "
                                     "(quoted keys are patterns, as in OpenFOAM)", pos)
                if tokens[self.i][0] == "{":
                    self.i += 1
                    sub = d.get(key)
                    new = not isinstance(sub, dict)
                    if new:
                        sub = {}
                    self.parse_dict(sub, scopes + [sub], tokens[self.i - 1][2])
                    if new:
                        d[key] = sub
                else:
                    items = self.items(scopes, ";", pos, key)
                    _assign(d, key, None if not items else items[0] if len(items) == 1 else tuple(items))
            elif kind == ";":
                continue
            elif kind == "dir":
                self.directive(value, pos, d, scopes)
            elif kind == "macro":
                if tokens[self.i][0] != ";":
                    raise self.error(f"expected ';' after macro entry {self.plain(value)}",
                                     tokens[self.i][2])
                self.i += 1
                sub = self.lookup(value, pos, scopes)
                if not isinstance(sub, dict):
                    raise self.error(f"macro entry {self.plain(value)}; does not refer to a "
                                     "dictionary", pos)
                for k, v in sub.items():
                    _assign(d, k, v)
            elif kind == "}" and open_pos is not None:
                self.nesting -= 1
                return
            elif kind == "eof":
                if open_pos is not None:
                    raise self.error("unterminated dictionary: missing '}'", open_pos)
                self.i -= 1
                self.nesting -= 1
                return
            else:
                raise self.error(f"expected a keyword, found {self.show(text)}", pos)

    def dimension_set(self, open_pos: int):
        """``[ ... ]``: seven (or five) numbers, or units/named dimensions."""
        tokens, j = self.tokens, self.i
        while tokens[j][0] not in ("]", ";", "{", "}", "eof"):
            j += 1
        if tokens[j][0] != "]":
            line, col = self.position(open_pos)
            raise self.error(f"unterminated dimension set opened at line {line}, column {col}: "
                             "missing ']'", open_pos if tokens[j][0] == "eof" else tokens[j][2])
        inner = tokens[self.i:j]
        close_pos = tokens[j][2]
        self.i = j + 1
        if all(t[0] == "num" for t in inner):
            return DimensionSet(t[1] for t in inner)
        raw = _COMMENTS_RE.sub(" ", self.text[open_pos + 1:close_pos]).strip()
        try:
            exps, factor = _units(raw)
        except ValueError as exc:
            raise self.error(
                f"dimension set must contain only numbers ([0 1 -1 0 0 0 0]) or units and named "
                f"dimensions ([m/s], [kg m^-3], [velocity]): {exc}; units: "
                f"{' '.join(UNITS)}; named dimensions: {' '.join(DIMENSIONS)}", open_pos) from None
        return DimensionSet(exps, units=" ".join(raw.split()), factor=factor)

    def items(self, scopes: list[dict], close: str, open_pos: int, key: str | None = None) -> list:
        """Parse value items up to ``close``: ';' ends an entry's value, ')' a list,
        ']' a dimension set and '}' a uniform list's value."""
        tokens = self.tokens
        out: list = []
        append = out.append
        self.enter(open_pos)
        dims_line = 0  # line of a dimension set in this entry's value (0: none yet)
        while True:
            kind, value, pos, text = tokens[self.i]
            self.i += 1
            if kind == "num":
                if type(value) is int and value >= 0:
                    nkind, _, npos, _ = tokens[self.i]
                    end = pos + len(text)
                    if nkind == "(" and (npos == end or self.text.find("\n", end, npos) >= 0):
                        self.i += 1
                        lst = self.items(scopes, ")", npos)
                        if len(lst) != value:
                            raise self.error(
                                f"list size mismatch: prefix says {value} items, found {len(lst)}", pos)
                        append(lst)
                        continue
                    if nkind == "{" and npos == end:
                        self.i += 1
                        inner = self.items(scopes, "}", npos)
                        if len(inner) != 1:
                            raise self.error(f"uniform list {value}{{...}} needs exactly one value", npos)
                        append([_copy(inner[0]) for _ in range(value)])
                        continue
                append(value)
            elif kind == "word" or kind == "str":
                if dims_line and kind == "word" and close == ";":
                    line = self.position(pos)[0]
                    if line > dims_line and self.text.rfind("\n", 0, pos) > tokens[self.i - 2][2]:
                        prev = tokens[self.i - 2]
                        raise self.error(
                            f"expected ';' after value of {self.show(key)} (a dimension set, "
                            f"then {self.show(text)} on line {line})", prev[2] + len(prev[3]))
                append(value)
            elif kind == "array":
                append(value)
            elif kind == close:
                self.nesting -= 1
                return out
            elif kind == "(":
                append(self.items(scopes, ")", pos))
            elif kind == "[":
                append(self.dimension_set(pos))
                dims_line = self.position(pos)[0]
            elif kind == "macro":
                value = self.lookup(value, pos, scopes)
                if type(value) is tuple:
                    out.extend(value)
                elif value is not None:
                    append(value)
            elif kind == "{" and close == ")":
                sub: dict = {}
                self.parse_dict(sub, scopes + [sub], pos)
                append(sub)
            elif kind == "dir":
                if value in _CODE_DIRECTIVES:
                    raise self.error(f"unsupported directive {value} inside a value: {_NEVER_CODE}",
                                     pos)
                raise self.error(f"unsupported directive {value} inside a value", pos)
            elif close == ";":
                raise self.error(f"expected ';' after value of {self.show(key)}", pos)
            elif kind == "eof":
                raise self.error(f"unterminated {_CLOSE_NAMES[close]}: missing {close!r}", open_pos)
            else:
                line, col = self.position(open_pos)
                raise self.error(f"unexpected {self.show(text)} in {_CLOSE_NAMES[close]} "
                                 f"opened at line {line}, column {col}", pos)

    def resolve_path(self, name: str, pos: int) -> Path:
        """An ``#include`` (or ``$file!entry``) path: ``$FOAM_CASE``/``$FOAM_CASENAME``
        expanded, relative paths from the including file's directory and kept inside the
        case directory (when it is known); an absolute path is taken as named."""
        try:
            expanded = expand(name, self.case_dir)
        except ValueError as exc:
            raise self.error(str(exc), pos) from None
        if "$" in expanded or expanded.startswith("~"):
            raise self.error(f"path {self.show(name)}: only $FOAM_CASE and $FOAM_CASENAME are "
                             "expanded in paths (no other environment variables, no '~')", pos)
        path = Path(expanded)
        named_absolute = Path(name).is_absolute()
        if not path.is_absolute():
            path = self.include_dir / path
        if self.case_dir is not None and not named_absolute:
            try:
                path.resolve().relative_to(Path(self.case_dir).resolve())
            except ValueError:
                raise self.error(f"path {self.show(name)} leads outside the case directory "
                                 f"{self.case_dir}; name an absolute path to use a file outside "
                                 "the case on purpose", pos) from None
        return path

    def read_other(self, name: str, pos: int, if_present: bool = False):
        """Text of another file named by this one, or None (missing, ``if_present``)."""
        path = self.resolve_path(name, pos)
        if if_present and not os.path.lexists(path):
            return path, None
        if self.depth >= _MAX_INCLUDE_DEPTH:
            raise self.error("#include nested too deeply (recursive include?)", pos)
        try:
            return path, read_text(path)
        except FoamDictError as exc:
            raise self.error(f"cannot read included file '{path}': {exc.message}", pos) from None

    def directive(self, name: str, pos: int, d: dict, scopes: list[dict]) -> None:
        if name in _CODE_DIRECTIVES:
            raise self.error(f"unsupported directive {name}: {_NEVER_CODE}", pos)
        kind, value, vpos, text = self.tokens[self.i]
        self.i += 1
        if name in ("#include", "#includeIfPresent"):
            if kind not in ("str", "word"):
                raise self.error(f"expected a file name after {name}", vpos)
            path, content = self.read_other(value, vpos, if_present=name == "#includeIfPresent")
            if content is None:
                return
            _Parser(content, str(path), path.parent, self.depth + 1, self.case_dir,
                    self.syntax, self.nesting).parse_dict(d, scopes)
        elif name == "#remove":
            keys = []
            if kind == "(":
                while self.tokens[self.i][0] in ("word", "num", "str"):
                    keys.append(self.tokens[self.i][1 if self.tokens[self.i][0] == "str" else 3])
                    self.i += 1
                if self.tokens[self.i][0] != ")":
                    raise self.error("expected keys and ')' after '#remove ('", self.tokens[self.i][2])
                self.i += 1
            elif kind in ("word", "num", "str"):
                keys.append(value if kind == "str" else text)
            else:
                raise self.error("expected a key or '(' after #remove", vpos)
            for k in keys:
                d.pop(k, None)
                if isinstance(k, QuotedString) and _regex(k) is not None:
                    for other in [x for x in d if _regex(k).fullmatch(x)]:
                        del d[other]
        elif name == "#inputMode":
            if kind != "word":
                raise self.error("expected a mode after #inputMode", vpos)
        elif name == "#inputSyntax":
            if kind != "word" or value not in ("slash", "dot"):
                raise self.error("expected 'slash' or 'dot' after #inputSyntax", vpos)
            self.syntax = value
        else:
            raise self.error(f"unsupported directive {name} (sphfoam reads #include, "
                             "#includeIfPresent, #remove, #inputMode and #inputSyntax)", pos)

    def lookup(self, macro: str, pos: int, scopes: list[dict]):
        """Value of ``$name`` / ``${name}`` (a deep copy)."""
        name = macro[2:-1] if macro.startswith("${") else macro[1:]
        if self.syntax == "slash" or (self.syntax == "auto" and ("/" in name or "!" in name)):
            candidates, parts = self.slash_scope(name, macro, pos, scopes)
            walk = _walk
        else:
            if name.startswith(":"):
                name, candidates = name[1:], [scopes[0]]
            else:
                dots = len(name) - len(name.lstrip("."))
                name, up = name[dots:], max(dots - 1, 0)
                if up >= len(scopes):
                    raise self.error(f"macro {self.plain(macro)} goes above the top level", pos)
                candidates = scopes[len(scopes) - 1 - up::-1]
            parts = name.split(".")
            walk = _descend
        if not parts or not all(parts):
            raise self.error(f"invalid macro name {self.plain(macro)}", pos)
        for scope in candidates:
            found, value = walk(scope, parts)
            if found:
                return _copy(value)
        if parts[0] in ("FOAM_CASE", "FOAM_CASENAME"):
            # Not a dictionary entry: OpenFOAM falls back to the environment variable.
            if self.case_dir is None:
                raise self.error(f"{macro} is used but the case directory is not known", pos)
            return QuotedString(expand("$" + "/".join(parts), self.case_dir))
        raise self.error(f"unknown macro {self.plain(macro)}", pos)

    def slash_scope(self, name: str, macro: str, pos: int, scopes: list[dict]):
        """Scopes to search and the '/'-separated parts of a slash-syntax reference:
        ``$a/b``, ``$../a`` (parent), ``$!a/b`` (top level), ``$file!a/b`` (another file)."""
        if "!" in name:
            file, _, rest = name.partition("!")
            if file:
                path, content = self.read_other(file, pos)
                other: dict = {}
                _Parser(content, str(path), path.parent, self.depth + 1, self.case_dir,
                        self.syntax, self.nesting).parse_dict(other, [other])
                candidates = [other]
            else:
                candidates = [scopes[0]]
            return candidates, rest.split("/")
        parts = name.split("/")
        up = 0
        while parts and parts[0] in ("..", "."):
            up += parts.pop(0) == ".."
        if up >= len(scopes):
            raise self.error(f"macro {self.plain(macro)} goes above the top level", pos)
        return scopes[len(scopes) - 1 - up::-1], parts


def parse(text: str, filename: str | None = None, include_dir: Path | None = None,
          case_dir: Path | None = None) -> dict:
    """Parse dictionary text into a plain (ordered) ``dict``.

    ``include_dir`` is where relative ``#include`` paths are looked up; by
    default the directory of ``filename``, else the current directory.
    ``case_dir`` is the case directory (``$FOAM_CASE``; relative includes must stay
    inside it); by default the nearest ancestor of ``include_dir`` holding a ``system``
    directory, if any.
    """
    if include_dir is None:
        include_dir = Path(filename).parent if filename else Path.cwd()
    include_dir = Path(include_dir)
    if case_dir is None:
        case_dir = _find_case(include_dir)
    result: dict = {}
    _Parser(text, filename, include_dir, case_dir=case_dir).parse_dict(result, [result])
    return result


def read(path, filename: str | None = None, case_dir: Path | None = None) -> dict:
    """Read and parse a dictionary file (errors name ``filename``, by default ``path``).

    Refuses directories, special files, oversized, binary and non-UTF-8 files with a
    :class:`FoamDictError` (see :func:`read_text`)."""
    path = Path(path)
    name = str(path) if filename is None else filename
    return parse(read_text(path, name), filename=name, include_dir=path.parent,
                 case_dir=case_dir)


# ----------------------------------------------------------------------------
# Writer
# ----------------------------------------------------------------------------

_INDENT = "    "
_KEY_WIDTH = 15
_INLINE_WIDTH = 72
_COUNT_THRESHOLD = 10
_BANNER = (
    "/*--------------------------------*- C++ -*----------------------------------*\\\n"
    "| sphfoam: SPH for free-surface water flows                                   |\n"
    "\\*---------------------------------------------------------------------------*/"
)
_SEPARATOR = "// " + "* " * 37 + "//"
_END = "// " + "*" * 73 + " //"


def _is_word(s: str) -> bool:
    return bool(_WORD_RE.fullmatch(s)) and not _INT_RE.fullmatch(s) and not _FLOAT_RE.fullmatch(s)


def _quote(s: str) -> str:
    return '"' + s.replace("\\", "\\\\").replace('"', '\\"') + '"'


def _is_count(x) -> bool:
    """True for items written as a non-negative int (a following '(' would read as a count)."""
    return isinstance(x, numbers.Integral) and not isinstance(x, bool) and x >= 0


def _number(x) -> str:
    if isinstance(x, numbers.Integral) and not isinstance(x, bool):
        return str(int(x))
    if isinstance(x, numbers.Real) and not isinstance(x, bool):
        f = float(x)
        if not math.isfinite(f):
            raise ValueError(f"cannot write non-finite float {f!r}")
        return repr(f)
    raise TypeError(f"expected a number, got {x!r}")


def _scalar(v) -> str:
    if isinstance(v, QuotedString):
        return _quote(v)
    if isinstance(v, str):
        if not _is_word(v):
            raise ValueError(f"{v!r} is not a valid word; use QuotedString to write it quoted")
        return v
    if isinstance(v, DimensionSet):
        if v.units is not None:
            return "[" + v.units + "]"
        return "[" + " ".join(_number(x) for x in v) + "]"
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, numbers.Real):
        return _number(v)
    raise TypeError(f"cannot write a value of type {type(v).__name__}: {v!r}")


def _item_lines(v, counted: bool = False) -> list[str]:
    """Lines (without base indentation) for a list item or tuple item."""
    if isinstance(v, list) or (hasattr(v, "tolist") and getattr(v, "ndim", 0) > 0):
        return _list_lines(list(v), counted)
    if isinstance(v, dict):
        lines = ["{"]
        _write_entries(v, _INDENT, lines)
        lines.append("}")
        return lines
    if v is None or type(v) is tuple:
        raise ValueError(f"cannot write {v!r} inside a list or tuple")
    return [_scalar(v)]


def _list_lines(items: list, counted: bool) -> list[str]:
    rendered, prev_count = [], False
    for x in items:
        rendered.append(_item_lines(x, prev_count))
        prev_count = _is_count(x)
    if all(len(r) == 1 for r in rendered) and not any(isinstance(x, list) for x in items):
        inline = "(" + " ".join(r[0] for r in rendered) + ")"
        if len(inline) <= _INLINE_WIDTH:
            return [f"{len(items)}{inline}" if counted else inline]
    lines = [str(len(items))] if counted or len(items) > _COUNT_THRESHOLD else []
    lines.append("(")
    lines.extend(_INDENT + line for r in rendered for line in r)
    lines.append(")")
    return lines


def _value_lines(v) -> list[str]:
    """Lines (without base indentation) for an entry's value."""
    if type(v) is not tuple:
        return _item_lines(v)
    if len(v) < 2:
        raise ValueError(f"a tuple value needs at least two items, got {v!r}")
    lines, current, prev_count = [], [], False
    for x in v:
        if isinstance(x, dict):
            raise ValueError(f"cannot write a dict inside a tuple: {v!r}")
        r = _item_lines(x, prev_count)
        prev_count = _is_count(x)
        if len(r) == 1:
            current.append(r[0])
        else:
            if current:
                lines.append(" ".join(current))
            lines.extend(r[:-1])
            # the next items go on after the closing line: a word on a line of its own
            # after a dimension set reads as a missing ';' (the parser's check)
            current = [r[-1]]
    if current:
        lines.append(" ".join(current))
    return lines


def _key(k) -> str:
    if not isinstance(k, str):
        raise TypeError(f"dictionary keys must be str, got {k!r}")
    if isinstance(k, QuotedString) or not (_WORD_RE.fullmatch(k) or _FLOAT_RE.fullmatch(k)):
        return _quote(k)
    return k


def _write_entries(d: dict, indent: str, out: list[str], top: bool = False) -> None:
    for key, value in d.items():
        k = _key(key)
        if isinstance(value, dict):
            out += [indent + k, indent + "{"]
            _write_entries(value, indent + _INDENT, out)
            out.append(indent + "}")
            if top:
                out.append("")
        elif value is None:
            out.append(f"{indent}{k};")
        else:
            lines = _value_lines(value)
            if len(lines) == 1:
                out.append(f"{indent}{k:<{_KEY_WIDTH}} {lines[0]};")
            else:
                if type(value) is tuple:
                    out.append(f"{indent}{k:<{_KEY_WIDTH}} {lines[0]}")
                    lines = lines[1:]
                else:
                    out.append(indent + k)
                out.extend(indent + line for line in lines)
                out[-1] += ";"
                if top:
                    out.append("")


def dumps(d: dict, header: dict | None = None) -> str:
    """Write ``d`` as dictionary text that :func:`parse` reads back equal.

    With ``header``, a banner and a ``FoamFile`` block (defaults: version 2.0,
    format ascii, class dictionary, then the given fields) come first, and any
    ``FoamFile`` entry of ``d`` is left out.
    """
    out: list[str] = []
    if header is not None:
        foamfile = {"version": 2.0, "format": "ascii", "class": "dictionary", **header}
        out.append(_BANNER)
        _write_entries({"FoamFile": foamfile}, "", out)
        out += [_SEPARATOR, ""]
        d = {k: v for k, v in d.items() if k != "FoamFile"}
    _write_entries(d, "", out, top=True)
    while out and out[-1] == "":
        out.pop()
    if header is not None:
        out += ["", _END]
    return "\n".join(out) + "\n"


def write(path, d: dict, header: dict | None = None) -> None:
    """Write ``dumps(d, header)`` to ``path``, creating parent directories."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(dumps(d, header))
