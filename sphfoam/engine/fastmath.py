"""The LLVM fast-math flags of every compiled kernel.

All of ``fastmath=True`` except ``reassoc``: no NaN/inf assumptions (``nnan``, ``ninf``: the
stability checks test for them outside the kernels), signed zeros ignored (``nsz``),
reciprocals and approximate functions allowed (``arcp``, ``afn``), fused multiply-add
contraction allowed (``contract``).

Why not ``reassoc``: with it, the machine code numba loads from its on-disk cache is not the
code it runs right after compiling. The same pair loop (C-SPH's moment sums with the Wendland
C2 kernel) then gives results differing in the last bits between a run that compiled its
pipeline and one that loaded it from the cache (7e-12 in the moment matrix after one pre-pass,
5e-10 Pa in p after 50 steps of the dam break), and restarts and comparisons across runs stop
being bitwise. Without ``reassoc`` the cold and cached results are bit-identical (and numba's
cache key does not include the fast-math flags, so the pipeline source itself must carry the
set). Floating-point sums are then evaluated in source order.
"""

FASTMATH = frozenset({"nnan", "ninf", "nsz", "arcp", "contract", "afn"})
#: the same set as Python source, for generated code: ``@njit(fastmath=<this>)``
FASTMATH_SOURCE = "{" + ", ".join(repr(f) for f in sorted(FASTMATH)) + "}"
