"""The runtime pipeline of the CPU backend: the compiled functions of one selection.

:class:`Pipeline` holds the generated module (:mod:`sphfoam.engine.emit_cpu`, built by
:mod:`sphfoam.engine.build`) and the coefficient vector its functions read, and runs what is
done between them on the host: the neighbour list's offsets, the half lists' bands.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numba
import numpy as np

from sphfoam.engine.neighbours import (BLOCK_COLOURS, deal_bands, deal_blocks, half_blocks,
                                       half_lists)
from sphfoam.engine.plan import Selection

#: bands of cell rows of the half-list loops (about equal particle counts, but never less than
#: a row, so a shallow tank has about as many as it has rows of water, and one band for the
#: near-empty rows above): numba's prange hands each thread a contiguous share of a colour's
#: bands, so they are listed dealt in turn (``deal_bands``: thread t's share holds the
#: colour's bands t, t + T, ...), not in row order, which gave the bed's rows to one thread
#: and the rows above the water to the other; a fixed number (not one per thread) keeps
#: every sum's order, and so the results, the same whatever the thread count. In 3-D the
#: bands are slabs of layers of cells, and a layer's band is cut into blocks of rows in four
#: colours, dealt by work (``half_blocks``, ``deal_blocks``): a shallow flow's few layers of
#: water still give each thread its share
HALF_BANDS = 64

#: the fixed scalar slots every pipeline reads from ``prm`` before the models' own (2-D)
CORE_PARAMS = ("h", "inv_h", "support2", "eta2", "gx", "gy")


def core_param_names(dim: int = 2) -> tuple[str, ...]:
    """The fixed scalar slots of a pipeline in ``dim`` dimensions (gravity per component)."""
    return CORE_PARAMS + (("gz",) if dim == 3 else ())


@dataclass
class Pipeline:
    """The compiled functions of one selection and the coefficient vector they read."""

    module: object
    prm: np.ndarray
    source_path: Path
    compile_seconds: float
    cache_hit: bool
    selection: Selection
    #: h, support radius (m) and the rest of :func:`core_parameters`
    core: dict | None = None
    #: list no pair of two non-fluid particles (the module's FLUID_PAIRS_ONLY; False lists
    #: every pair within reach, as before: the same results, a longer list)
    fluid_pairs_only: bool = False

    @property
    def h(self) -> float:
        if self.core is not None:
            return float(self.core["h"])
        return float(self.prm[CORE_PARAMS.index("h")])

    @property
    def support_radius(self) -> float:
        if self.core is not None:
            return float(np.sqrt(self.core["support2"]))
        return float(np.sqrt(self.prm[CORE_PARAMS.index("support2")]))

    @property
    def dtype(self):
        """The numpy type of the state arrays, ``aux`` and ``prm`` the functions take."""
        return self.prm.dtype

    @property
    def equation_of_state(self):
        return self.module.equation_of_state

    @property
    def rates(self):
        return self.module.rates

    @property
    def density_rate(self):
        return self.module.density_rate

    def neighbour_list(self, x, y, kind, cells, reach: float, start=None, idx=None, z=None):
        """(nb_start, nb_idx): the neighbours of every particle within ``reach`` (at most
        the cell side), found by one walk of the cells; ``start``/``idx`` are reused when
        large enough. Where ``fluid_pairs_only``, no pair of two non-fluid particles. ``z``:
        the third coordinate of a three-dimensional case."""
        n = x.shape[0]
        count = np.empty(n, dtype=np.int64)
        coords = (x, y) if z is None else (x, y, z)
        args = (*coords, kind, bool(self.fluid_pairs_only), cells.cell_start, *cells.grid(),
                self.prm, reach * reach)
        self.module.count_neighbours(*args, count)
        if start is None or start.shape[0] != n + 1:
            start = np.empty(n + 1, dtype=np.int64)
        start[0] = 0
        np.cumsum(count, out=start[1:])
        total = int(start[-1])
        if idx is None or idx.shape[0] < total:
            idx = np.empty(int(total * 1.1) + 16, dtype=np.uint32)
        self.module.fill_neighbours(*args, start, idx)
        return start, idx

    def deal_bands(self, half, threads: int, nb_start):
        """Deal the bands of ``half`` to ``threads`` threads anew (``deal_bands``;
        ``deal_blocks`` in 3-D, by the work of the list ``nb_start``)."""
        if self.selection.dim == 3:
            deal_blocks(half, half.shape[0] - 2 * int(half[-1]) - 2 - BLOCK_COLOURS, threads,
                        nb_start)
        else:
            deal_bands(half, half.shape[0] - 2 * int(half[-1]) - 2, threads)

    def half_lists(self, nb_start, nb_idx, cells, half=None):
        """The array ``half`` of the half-list loops ``rates_half``/``density_half``: where
        each particle's neighbours b > a start in its list, the first particle of each band
        of cell rows (see :func:`sphfoam.engine.neighbours.half_lists`), the order the loops
        run each colour's bands in, dealt to numba's threads now
        (:func:`~sphfoam.engine.neighbours.deal_bands`), and the number of bands; None when the selection
        has no such loops or the list does not allow them. ``half`` is reused if it fits.
        (One array, not two: the loops then take 19 arguments, and CPython keeps freed
        tuples of up to 20 items, which the no-allocation check of tests/test_speed.py
        would count.)"""
        if self.rates_half is None and self.density_half is None:
            return None
        n = nb_start.shape[0] - 1
        # the bands: cell rows along x in 2-D; in 3-D blocks of rows within layers of cells
        rows = cells.ncy if cells.dim == 2 else cells.ncy * cells.ncz
        extra = 0 if cells.dim == 2 else BLOCK_COLOURS
        size = n + 2 * rows + 2 + extra
        if nb_start[-1] >= 2 ** 32:
            return None
        if half is None or half.base is None or half.base.shape[0] != size:
            buf = np.empty(size, dtype=np.uint32)
        else:
            buf = half.base
        if cells.dim == 2:
            nb = half_lists(nb_start, nb_idx, cells.cell_start, cells.ncx, rows,
                            HALF_BANDS, buf[:n], buf[n:n + rows + 1])
        else:
            nb = half_blocks(nb_start, nb_idx, cells.cell_start, cells.ncx, cells.ncy,
                             cells.ncz, not self.selection.periodic("y"), HALF_BANDS,
                             buf[:n], buf[n:])
        if not nb:
            return None
        half = buf[:n + 2 * nb + 2 + extra]
        half[-1] = nb
        if cells.dim == 2:
            deal_bands(half, n, numba.get_num_threads())
        else:
            deal_blocks(half, n, numba.get_num_threads(), nb_start)
        return half

    @property
    def rates_half(self):
        """``rates`` over half lists, or None when a selected term has no reaction."""
        return getattr(self.module, "rates_half", None)

    @property
    def density_half(self):
        """``density_rate`` over half lists, or None."""
        return getattr(self.module, "density_half", None)

    @property
    def prepass(self):
        """None when no selected model needs per-particle auxiliary fields."""
        return getattr(self.module, "prepass", None)

    @property
    def prepass_once(self) -> bool:
        """Whether the prepass runs once per step (``Plan.prepass_once``)."""
        return bool(getattr(self.module, "PREPASS_ONCE", False))

    @property
    def prepass_half(self):
        """``prepass`` over half lists, or None (see ``Plan.prepass_half_terms``)."""
        return getattr(self.module, "prepass_half", None)

    @property
    def prepass_sums(self) -> int:
        """Rows of the array of per-particle sums ``prepass_half`` takes."""
        return len(getattr(self.module, "PREPASS_SUMS", ()))

    @property
    def density_filter(self):
        return getattr(self.module, "density_filter", None)

    @property
    def step_pass(self):
        """None unless a selected model keeps a per-step state (the ``step`` stage)."""
        return getattr(self.module, "step_pass", None)

    @property
    def fields(self) -> tuple[str, ...]:
        return tuple(self.module.FIELDS)

    @property
    def pair_cache(self) -> tuple[str, ...]:
        """Pair scalars the prepass stores per listed pair for the later loops of an
        evaluation (``pc[J_<name>, k]``, an extra last argument of every pair loop)."""
        return tuple(getattr(self.module, "PAIR_CACHE", ()))

    def prepass_before(self, stage: str) -> bool:
        """Whether the prepass runs before the pass ``stage`` ("rates", "density",
        "filter"): always before the rates, before the others where they read what it
        makes."""
        return self.prepass is not None and stage in self.module.PREPASS_BEFORE

    @property
    def n_aux(self) -> int:
        return len(self.module.AUX)

    def aux_index(self, name: str) -> int:
        return list(self.module.AUX).index(name)
