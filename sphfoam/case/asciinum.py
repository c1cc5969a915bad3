"""Fast, exact reading of long whitespace-separated number lists (OpenFOAM ``List<T>``
bodies and ascii particle fields) straight into numpy arrays.

One numba pass over the bytes parses every number. A decimal ``d1...dn x 10^e`` whose
digits fit in 2^53 and with ``|e| <= 22`` is converted exactly (both factors are exact
doubles, so one IEEE multiplication or division rounds correctly: Clinger 1990, "How to
read floating point numbers accurately"); one with up to 18 digits is formed in
double-double arithmetic (Dekker 1971) and rounded, unless it lies too close to a
rounding midpoint to tell; any other number (and those) is handed to Python's correctly
rounded ``float``. The result is
therefore bit-for-bit what ``float(token)`` gives for every token.
"""

from __future__ import annotations

import functools
import math
import re

import numpy as np
from numba import njit

__all__ = ["parse_numbers"]

_POW10 = np.array([10.0 ** k for k in range(23)])  # 1e0 .. 1e22, all exact doubles
_TOKEN_END = re.compile(rb"[^\s()]*")
_PARENS = bytes.maketrans(b"()", b"  ")


_SPLIT = 134217729.0  # 2^27 + 1 (Veltkamp/Dekker splitting)


@njit(cache=True)
def _two_prod(a, b):
    """(p, e) with p = fl(a b) and p + e = a b exactly (Dekker 1971)."""
    p = a * b
    t = _SPLIT * a
    ah = t - (t - a)
    al = a - ah
    t = _SPLIT * b
    bh = t - (t - b)
    bl = b - bh
    return p, ((ah * bh - p) + ah * bl + al * bh) + al * bl


@njit(cache=True)
def _wide(mant, exp10, pow10, res):
    """``mant x 10^exp10`` for a 54-63 bit ``mant`` and ``|exp10| <= 22``, correctly
    rounded into ``res[0]``: the value is formed in double-double arithmetic (relative
    error below 2^-100) and rounded to nearest; False (leave it to Python) when it lies
    too close to a rounding midpoint to decide, or at a binade boundary."""
    a = float(mant >> 32) * 4294967296.0  # exact
    b = float(mant & 0xFFFFFFFF)  # exact
    s = a + b
    err = b - (s - a)  # a >= b: s + err = mant exactly (fast two-sum)
    big = pow10[exp10 if exp10 >= 0 else -exp10]
    if exp10 >= 0:
        p, pe = _two_prod(s, big)
        lo = pe + err * big
        hi = p
    else:
        q = s / big
        pp, pe = _two_prod(q, big)
        r = ((s - pp) - pe) + err  # s - pp is exact (Sterbenz)
        hi = q
        lo = r / big
    x = hi + lo
    t = lo - (x - hi)  # x + t = hi + lo
    m, e = math.frexp(x)
    ulp = math.ldexp(1.0, e - 53)
    if m == 0.5 and t < 0.0:
        return False
    if abs(abs(t) - 0.5 * ulp) <= ulp * 1e-9:
        return False
    res[0] = x
    return True


@njit(cache=True)
def _scan(buf, ncomp, integer, out, iout, fallback, fbslot, pow10):
    wide = np.empty(1)
    """Parse ``buf`` (uint8) into ``out`` (float64) or ``iout`` (int64, ``integer``).

    With ``ncomp > 1`` the numbers must come in ``(a b ...)`` groups of ``ncomp``; with
    ``ncomp == 1`` parentheses are not allowed. Returns (count, n_fallback, status):
    status 0 ok, 1 not a number list (or wrong grouping), 2 more numbers than ``out``
    holds. ``fallback`` receives the byte offsets of the numbers to convert in Python and
    ``fbslot`` their indices in the output.
    """
    n = buf.size
    cap = iout.size if integer else out.size
    i = 0
    count = 0
    nfb = 0
    in_group = False
    group = 0
    while i < n:
        c = buf[i]
        if c == 32 or (9 <= c <= 13):
            i += 1
            continue
        if c == 40:  # '('
            if ncomp == 1 or in_group:
                return count, nfb, 1
            in_group = True
            group = 0
            i += 1
            continue
        if c == 41:  # ')'
            if not in_group or group != ncomp:
                return count, nfb, 1
            in_group = False
            i += 1
            continue
        if ncomp > 1 and not in_group:
            return count, nfb, 1
        if count >= cap:
            return count, nfb, 2
        start = i
        neg = False
        if c == 43 or c == 45:  # '+' '-'
            neg = c == 45
            i += 1
        mant = 0
        ndig = 0  # significant digits kept in mant (18 fit in int64)
        nd = 0  # digits seen
        exp10 = 0
        overflow = False
        while i < n and 48 <= buf[i] <= 57:
            nd += 1
            if ndig < 18:
                if mant != 0 or buf[i] != 48:
                    ndig += 1
                mant = mant * 10 + (buf[i] - 48)
            else:
                overflow = True
            i += 1
        frac = False
        if i < n and buf[i] == 46:  # '.'
            frac = True
            i += 1
            while i < n and 48 <= buf[i] <= 57:
                nd += 1
                if ndig < 18:
                    if mant != 0 or buf[i] != 48:
                        ndig += 1
                    mant = mant * 10 + (buf[i] - 48)
                    exp10 -= 1
                else:
                    overflow = True
                i += 1
        if nd == 0:
            return count, nfb, 1
        has_exp = False
        if i < n and (buf[i] == 101 or buf[i] == 69):  # 'e' 'E'
            has_exp = True
            i += 1
            eneg = False
            if i < n and (buf[i] == 43 or buf[i] == 45):
                eneg = buf[i] == 45
                i += 1
            ed = 0
            e = 0
            while i < n and 48 <= buf[i] <= 57:
                if e < 100000:
                    e = e * 10 + (buf[i] - 48)
                ed += 1
                i += 1
            if ed == 0:
                return count, nfb, 1
            exp10 += -e if eneg else e
        if i < n and not (buf[i] == 32 or (9 <= buf[i] <= 13) or buf[i] == 40 or buf[i] == 41):
            return count, nfb, 1
        if integer:
            if frac or has_exp:
                return count, nfb, 1
            if overflow:
                fallback[nfb] = start
                fbslot[nfb] = count
                nfb += 1
                iout[count] = 0
            else:
                iout[count] = -mant if neg else mant
        elif not overflow and mant <= 9007199254740992 and -22 <= exp10 <= 22:
            v = float(mant)
            if exp10 >= 0:
                v = v * pow10[exp10]
            else:
                v = v / pow10[-exp10]
            out[count] = -v if neg else v
        elif not overflow and -22 <= exp10 <= 22 and _wide(mant, exp10, pow10, wide):
            out[count] = -wide[0] if neg else wide[0]
        else:
            fallback[nfb] = start
            fbslot[nfb] = count
            nfb += 1
            out[count] = 0.0
        count += 1
        if in_group:
            group += 1
    if in_group:
        return count, nfb, 1
    return count, nfb, 0


#: Inputs shorter than this (bytes) are read by regular expressions and numpy instead,
#: sparing a process the numba dispatch (and, with a cold cache, the compile) it would
#: pay once; both ways give the same, exact result.
COMPILED_MIN_BYTES = 1 << 20

_NUM = rb"[+-]?(?:[0-9]+\.?[0-9]*|\.[0-9]+)(?:[eE][+-]?[0-9]+)?"
_INT = rb"[+-]?[0-9]+"


@functools.lru_cache(maxsize=32)
def _layout(ncomp: int, integer: bool):
    num = _INT if integer else _NUM
    if ncomp == 1:
        item = num
    else:
        item = rb"\(\s*" + num + (rb"\s+" + num) * (ncomp - 1) + rb"\s*\)"
    return re.compile(rb"\s*(?:" + item + rb"(?:\s+|(?=[()])|\Z))*\s*")


def _parse_small(data: bytes, count: int, ncomp: int, integer: bool):
    if _layout(ncomp, integer).fullmatch(data) is None:
        return None
    tokens = data.translate(_PARENS).split()
    if len(tokens) != count:
        return None
    try:
        return np.array([int(t) for t in tokens] if integer else tokens,
                        dtype=np.int64 if integer else np.float64)
    except (ValueError, OverflowError):
        return None


def parse_numbers(text, count: int, ncomp: int = 1, integer: bool = False):
    """The ``count`` numbers of ``text`` (str or bytes) as a float64 (or int64) array of
    shape ``(count // ncomp, ncomp)`` (``(count,)`` when ``ncomp == 1``), or ``None`` when
    ``text`` is not exactly that: another token, a different count, or (``ncomp > 1``)
    numbers not grouped as ``(a b ...)`` tuples of ``ncomp``."""
    if isinstance(text, str):
        try:
            data = text.encode("ascii")
        except UnicodeEncodeError:
            return None
    else:
        data = bytes(text)
    if len(data) < COMPILED_MIN_BYTES:
        res = _parse_small(data, count, ncomp, integer)
        if res is None:
            return None
        return res.reshape(-1, ncomp) if ncomp > 1 else res
    buf = np.frombuffer(data, dtype=np.uint8)
    out = np.empty(0 if integer else count, dtype=np.float64)
    iout = np.empty(count if integer else 0, dtype=np.int64)
    fallback = np.empty(count, dtype=np.int64)
    fbslot = np.empty(count, dtype=np.int64)
    got, nfb, status = _scan(buf, ncomp, integer, out, iout, fallback, fbslot, _POW10)
    if status != 0 or got != count:
        return None
    res = iout if integer else out
    if nfb:
        convert = int if integer else float
        try:
            for start, slot in zip(fallback[:nfb].tolist(), fbslot[:nfb].tolist()):
                res[slot] = convert(_TOKEN_END.match(data, start).group(0))
        except (ValueError, OverflowError):
            return None
    return res.reshape(-1, ncomp) if ncomp > 1 else res
