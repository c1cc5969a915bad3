"""Reading large nonuniform lists: sphfoam's dictionary reader against numpy's text readers.

    python benchmarks/bench_foamdict.py            # 1 M vectors and 1 M scalars
    python benchmarks/bench_foamdict.py -n 200000  # smaller

For ``internalField nonuniform List<vector> N (...)`` written with 17 significant digits
(``%r``, bit-exact) and with 6 (``%.6g``, sphfoam's default ascii precision), and for a
``List<scalar>``, it times (best of ``--repeat``):

* ``foamdict.parse`` on the whole dictionary text (the list comes back as a numpy array);
* ``numpy.fromstring(body, sep=" ")`` on the list body with the parentheses blanked out
  (the reference "compiled reader"), and ``numpy.loadtxt`` on the same body;
* ``foamdict.parse`` with the array path switched off (``ARRAY_MIN_ITEMS`` raised), on a
  tenth of the items, scaled by 10: the general token-by-token reader that returns lists;
* ``sphfoam.io.fields.read_field`` on an ascii ``vector2DField`` particle file of the same
  size (numpy's own conversion of the split tokens).

It also checks that every array equals ``float(token)`` of every token bit for bit.
Nothing is written except a temporary field file.
"""

from __future__ import annotations

import argparse
import io
import tempfile
import time
from pathlib import Path

import numpy as np

from sphfoam.case import foamdict
from sphfoam.io.fields import read_field, write_field


def best(fn, repeat):
    out, t_best = None, float("inf")
    for _ in range(repeat):
        t0 = time.perf_counter()
        out = fn()
        t_best = min(t_best, time.perf_counter() - t0)
    return t_best, out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("-n", type=int, default=1_000_000, help="items per list (default 1e6)")
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args()
    n, rng = args.n, np.random.default_rng(0)
    vec = rng.standard_normal((n, 3))
    foamdict.parse("warm nonuniform List<vector> 100(" + "(1 2 3)" * 100 + ");")  # JIT / cache

    rows = []
    for label, fmt in (("vector, 17 digits", "%r"), ("vector, 6 digits", "%.6g")):
        item = f"({fmt} {fmt} {fmt})\n"
        body = "".join(item % tuple(r) for r in vec.tolist())
        text = f"internalField nonuniform List<vector>\n{n}\n(\n{body})\n;\n"
        ref = np.array([float(t) for t in body.replace("(", " ").replace(")", " ").split()])
        t_parse, d = best(lambda: foamdict.parse(text), args.repeat)
        arr = d["internalField"][2]
        assert isinstance(arr, np.ndarray) and arr.tobytes() == ref.tobytes()
        blank = body.translate(str.maketrans("()", "  "))
        t_from, a = best(lambda: np.fromstring(blank, sep=" "), args.repeat)
        assert a.tobytes() == ref.tobytes()
        t_load, _ = best(lambda: np.loadtxt(io.StringIO(blank)), 1)
        small = max(n // 10, 1)
        small_text = (f"internalField nonuniform List<vector>\n{small}\n(\n"
                      + "".join(item % tuple(r) for r in vec[:small].tolist()) + ")\n;\n")
        keep = foamdict.ARRAY_MIN_ITEMS
        foamdict.ARRAY_MIN_ITEMS = 10**18
        try:
            t_list, _ = best(lambda: foamdict.parse(small_text), 1)
        finally:
            foamdict.ARRAY_MIN_ITEMS = keep
        rows.append((label, t_parse, t_from, t_load, t_list * n / small))

    scal = "x nonuniform List<scalar> %d(" % n + " ".join("%r" % x for x in vec[:, 0].tolist()) + ");"
    t_parse, d = best(lambda: foamdict.parse(scal), args.repeat)
    assert d["x"][2].tobytes() == vec[:, 0].tobytes()
    body = scal[scal.index("(") + 1:-2]
    t_from, _ = best(lambda: np.fromstring(body, sep=" "), args.repeat)
    t_load, _ = best(lambda: np.loadtxt(io.StringIO(body.replace(" ", "\n"))), 1)
    rows.append(("scalar, 17 digits", t_parse, t_from, t_load, float("nan")))

    with tempfile.TemporaryDirectory() as tmp:
        f = Path(tmp) / "U"
        write_field(f, vec[:, :2].copy(), fmt="ascii", precision=17)
        t_field, a = best(lambda: read_field(f), args.repeat)
        assert a.tobytes() == vec[:, :2].tobytes()

    print(f"{n} items per list; seconds, best of {args.repeat}\n")
    print("| list | foamdict.parse | numpy.fromstring | numpy.loadtxt | general reader (lists) |")
    print("|---|---|---|---|---|")
    for label, *ts in rows:
        print(f"| {label} | " + " | ".join("-" if t != t else f"{t:.3f}" for t in ts) + " |")
    print(f"\nread_field, ascii vector2DField (17 digits): {t_field:.3f} s")


if __name__ == "__main__":
    main()
