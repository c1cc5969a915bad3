"""Reader and writer for OpenFOAM dictionary files.

The reader runs in linear time: one compiled regular expression splits the
text into tokens in a single pass, and a recursive-descent parser walks the
token list with an index. Line and column numbers are only worked out when an
error is reported.

Grammar
-------
::

    file       := entry*
    entry      := key '{' entry* '}' [';']      sub-dictionary
                | key item* ';'                 key value;  (no items -> None)
                | '$' name ';'                  merge a dictionary macro here
                | directive
                | ';'                           stray ';' (e.g. after '}'), skipped
    key        := word | number | "quoted"      (the token's text is the key)
    item       := number | word | "quoted" | '$' name
                | [count] '(' (item | '{' entry* '}')* ')'  list
                | count '{' item '}'            uniform list
                | '[' number* ']'               dimension set
    directive  := '#include' "file" | '#includeIfPresent' "file"
                | '#remove' key | '#remove' '(' key* ')' | '#inputMode' word

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
  ``[ ... ]`` -> :class:`DimensionSet`; ``key { ... }`` -> ``dict``.

Entries keep file order. A later scalar entry replaces an earlier one with the
same key; a later sub-dictionary is merged recursively into an earlier one.
``#include`` paths are relative to the directory of the file that includes
them, and the included entries are merged into the current dictionary.

Macros: ``$x`` or ``${x}`` is replaced by a deep copy of ``x``, looked up in
the current dictionary (as parsed so far) and then in the enclosing ones.
``$a.b.c`` looks up ``a`` that way and then goes down through ``b`` and ``c``.
``$:a.b`` starts at the top level. Leading dots choose where the search starts:
``$.x`` in the current dictionary, ``$..x`` in its parent, and each extra dot
one level further up. A multi-token macro value is spliced into the
surrounding items. A standalone ``$dict;`` entry merges the entries of
``dict`` into the current dictionary.

Not supported: ``#includeEtc``, ``#includeFunc``, ``#calc``, ``#codeStream``
and other directives, verbatim ``#{ ... #}`` blocks, ``$FOAM_CASE`` and other
environment variables in paths, ``/``-scoped macros (``$a/b``), regex or
wildcard matching of keys (for lookups and ``#remove``), ``$macro`` as a key,
unit names inside dimension sets (``[kg m^-1]``), and files whose top level
is a bare list (polyMesh files).

:func:`dumps` writes text that :func:`parse` reads back equal, with the same
types. It raises ``ValueError`` for values that have no exact text form: a
``str`` that is not a valid bare word (use :class:`QuotedString`), non-finite
floats, tuples with fewer than two items, tuples inside tuples or lists, and
``None`` or ``dict`` inside a tuple. ``True``/``False`` are written as the
words ``true``/``false``.
"""

from __future__ import annotations

import math
import numbers
import re
from pathlib import Path

__all__ = ["FoamDictError", "QuotedString", "DimensionSet", "parse", "read", "dumps", "write"]


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
    """A string that was (and will be written) in double quotes."""

    __slots__ = ()

    def __repr__(self) -> str:
        return f"QuotedString({str.__repr__(self)})"


class DimensionSet(tuple):
    """A dimension set such as ``[0 1 -1 0 0 0 0]``."""

    __slots__ = ()

    def __repr__(self) -> str:
        return f"DimensionSet({tuple.__repr__(self)})"


# ----------------------------------------------------------------------------
# Tokenizer
# ----------------------------------------------------------------------------

# A word: no whitespace, no ';(){}[]"', not starting with '$' or '#', and no
# '//' or '/*' inside (those start comments).
_WORD = r'(?:[^\s;(){}\[\]"/$#]|/(?![/*]))(?:[^\s;(){}\[\]"/]|/(?![/*]))*'
_TOKEN_RE = re.compile(
    r'\s*(?:'
    r'(?P<comment>//[^\n]*|/\*.*?\*/)'
    r'|(?P<opencomment>/\*)'
    r'|(?P<str>"(?:[^"\\]|\\.)*")'
    r'|(?P<openstr>")'
    r'|(?P<punct>[;(){}\[\]])'
    r'|(?P<dir>#[A-Za-z]\w*)'
    r'|(?P<macro>\$(?:\{[^{}\s]*\}|[^\s;(){}\[\]"$#/]+))'
    r'|(?P<word>' + _WORD + r')'
    r'|(?P<bad>\S)'
    r')', re.S)
_WORD_RE = re.compile(_WORD)
_INT_RE = re.compile(r'[+-]?[0-9]+')
_FLOAT_RE = re.compile(r'[+-]?(?:[0-9]+\.[0-9]*|\.[0-9]+|[0-9]+)(?:[eE][+-]?[0-9]+)?')
_UNESCAPE_RE = re.compile(r'\\([\\"])')
_NUMBER_START = frozenset("0123456789+-.")

# A token is (kind, value, position, text). Kinds: 'num', 'word', 'str',
# 'macro', 'dir', one of ';(){}[]' for punctuation, and 'eof'.


def _tokenize(text: str, error) -> list[tuple]:
    tokens: list[tuple] = []
    append = tokens.append
    end = 0
    for m in _TOKEN_RE.finditer(text):
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
            append(("word", s, pos, s))
        elif kind == "punct":
            append((s, s, pos, s))
        elif kind == "comment":
            pass
        elif kind == "str":
            append(("str", QuotedString(_UNESCAPE_RE.sub(r"\1", s[1:-1])), pos, s))
        elif kind in ("macro", "dir"):
            append((kind, s, pos, s))
        elif kind == "opencomment":
            raise error("unterminated comment", pos)
        elif kind == "openstr":
            raise error("unterminated string", pos)
        else:
            raise error(f"unexpected character {s!r}", pos)
    append(("eof", None, end, "end of file"))
    return tokens


# ----------------------------------------------------------------------------
# Parser
# ----------------------------------------------------------------------------

_CLOSE_NAMES = {")": "list", "]": "dimension set", "}": "uniform list"}
_MAX_INCLUDE_DEPTH = 32


def _copy(value):
    """Deep copy of a parsed value (containers only; scalars are immutable)."""
    if isinstance(value, dict):
        return {k: _copy(v) for k, v in value.items()}
    if isinstance(value, list):
        return [_copy(v) for v in value]
    if type(value) is tuple:
        return tuple(_copy(v) for v in value)
    return value


def _assign(d: dict, key: str, value) -> None:
    """Set an entry: sub-dicts merge recursively, anything else replaces."""
    old = d.get(key)
    if isinstance(value, dict) and isinstance(old, dict):
        for k, v in value.items():
            _assign(old, k, v)
    else:
        d[key] = value


def _descend(d: dict, parts: list[str]):
    """Find ``parts`` (a dotted name split on '.') in ``d``; keys may contain dots."""
    for n in range(len(parts), 0, -1):
        key = ".".join(parts[:n])
        if key in d:
            if n == len(parts):
                return True, d[key]
            if isinstance(d[key], dict):
                found, value = _descend(d[key], parts[n:])
                if found:
                    return True, value
    return False, None


class _Parser:
    def __init__(self, text: str, filename: str | None, include_dir: Path, depth: int = 0):
        self.text, self.filename, self.include_dir, self.depth = text, filename, include_dir, depth
        self.tokens = _tokenize(text, self.error)
        self.i = 0

    def position(self, pos: int) -> tuple[int, int]:
        return self.text.count("\n", 0, pos) + 1, pos - self.text.rfind("\n", 0, pos)

    def error(self, message: str, pos: int) -> FoamDictError:
        return FoamDictError(message, self.filename, *self.position(pos))

    def parse_dict(self, d: dict, scopes: list[dict], open_pos: int | None = None) -> None:
        """Parse entries into ``d`` up to the matching '}' (or end of file if top level).

        ``scopes`` lists the dictionaries being built, outermost first, ``d`` last.
        """
        tokens = self.tokens
        while True:
            kind, value, pos, text = tokens[self.i]
            self.i += 1
            if kind in ("word", "num", "str"):
                key = value if kind == "str" else text
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
                    raise self.error(f"expected ';' after macro entry {value}", tokens[self.i][2])
                self.i += 1
                sub = self.lookup(value, pos, scopes)
                if not isinstance(sub, dict):
                    raise self.error(f"macro entry {value}; does not refer to a dictionary", pos)
                for k, v in sub.items():
                    _assign(d, k, v)
            elif kind == "}" and open_pos is not None:
                return
            elif kind == "eof":
                if open_pos is not None:
                    raise self.error("unterminated dictionary: missing '}'", open_pos)
                self.i -= 1
                return
            else:
                raise self.error(f"expected a keyword, found {text!r}", pos)

    def items(self, scopes: list[dict], close: str, open_pos: int, key: str | None = None) -> list:
        """Parse value items up to ``close``: ';' ends an entry's value, ')' a list,
        ']' a dimension set and '}' a uniform list's value."""
        tokens = self.tokens
        out: list = []
        append = out.append
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
                append(value)
            elif kind == close:
                return out
            elif kind == "(":
                append(self.items(scopes, ")", pos))
            elif kind == "[":
                dims = self.items(scopes, "]", pos)
                if not all(type(x) in (int, float) for x in dims):
                    raise self.error("dimension set must contain only numbers", pos)
                append(DimensionSet(dims))
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
                raise self.error(f"unsupported directive {value} inside a value", pos)
            elif close == ";":
                raise self.error(f"expected ';' after value of {key!r}", pos)
            elif kind == "eof":
                raise self.error(f"unterminated {_CLOSE_NAMES[close]}: missing {close!r}", open_pos)
            else:
                line, col = self.position(open_pos)
                raise self.error(f"unexpected {text!r} in {_CLOSE_NAMES[close]} "
                                 f"opened at line {line}, column {col}", pos)

    def directive(self, name: str, pos: int, d: dict, scopes: list[dict]) -> None:
        kind, value, vpos, text = self.tokens[self.i]
        self.i += 1
        if name in ("#include", "#includeIfPresent"):
            if kind not in ("str", "word"):
                raise self.error(f"expected a file name after {name}", vpos)
            path = Path(value)
            if not path.is_absolute():
                path = self.include_dir / path
            try:
                content = path.read_text()
            except OSError as exc:
                if name == "#includeIfPresent":
                    return
                raise self.error(f"cannot read included file '{path}': {exc.strerror}", vpos) from None
            if self.depth >= _MAX_INCLUDE_DEPTH:
                raise self.error("#include nested too deeply (recursive include?)", pos)
            _Parser(content, str(path), path.parent, self.depth + 1).parse_dict(d, scopes)
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
        elif name == "#inputMode":
            if kind != "word":
                raise self.error("expected a mode after #inputMode", vpos)
        else:
            raise self.error(f"unsupported directive {name}", pos)

    def lookup(self, macro: str, pos: int, scopes: list[dict]):
        """Value of ``$name`` / ``${name}`` (a deep copy)."""
        name = macro[2:-1] if macro.startswith("${") else macro[1:]
        if name.startswith(":"):
            name, candidates = name[1:], [scopes[0]]
        else:
            dots = len(name) - len(name.lstrip("."))
            name, up = name[dots:], max(dots - 1, 0)
            if up >= len(scopes):
                raise self.error(f"macro {macro} goes above the top level", pos)
            candidates = scopes[len(scopes) - 1 - up::-1]
        parts = name.split(".")
        if not all(parts):
            raise self.error(f"invalid macro name {macro}", pos)
        for scope in candidates:
            found, value = _descend(scope, parts)
            if found:
                return _copy(value)
        raise self.error(f"unknown macro {macro}", pos)


def parse(text: str, filename: str | None = None, include_dir: Path | None = None) -> dict:
    """Parse dictionary text into a plain (ordered) ``dict``.

    ``include_dir`` is where relative ``#include`` paths are looked up; by
    default the directory of ``filename``, else the current directory.
    """
    if include_dir is None:
        include_dir = Path(filename).parent if filename else Path.cwd()
    result: dict = {}
    _Parser(text, filename, Path(include_dir)).parse_dict(result, [result])
    return result


def read(path) -> dict:
    """Read and parse a dictionary file."""
    path = Path(path)
    return parse(path.read_text(), filename=str(path), include_dir=path.parent)


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
                current = []
            lines.extend(r)
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
