"""Particle state as a struct of arrays."""

from __future__ import annotations

import numpy as np

#: particle kinds (the ``type`` field of a time directory); ghosts (mirrored across walls
#: each step, T(3.77)) live only inside a step and are never written
FLUID, WALL, GHOST = 0, 1, 2

#: persistent arrays (permuted when particles are re-sorted, written to time directories)
PERSISTENT_F8 = ("x", "y", "u", "v", "rho", "m")
PERSISTENT_I8 = ("kind", "id")
#: per-step work arrays (recomputed, never written)
SCRATCH = ("p", "c", "ax", "ay", "drho", "sigma")

#: arrays held in the working precision (``sphSchemes`` ``precision``): everything but the
#: positions, the kind/id and the extra fields, which stay double (positions as DualSPHysics
#: keeps them: relative positions are formed in double, then rounded)
WORKING = ("u", "v", "rho", "m")


def kept_arrays(owner, name: str, k: int, n: int, dtype=np.float64) -> tuple:
    """k arrays of n ``dtype`` that ``owner`` keeps as attribute ``name`` between calls and
    makes anew only when n or the dtype changed: a model's per-step work arrays without an
    allocation a step. Their contents are the caller's: valid until its next call."""
    buf = getattr(owner, name, None)
    if buf is None or len(buf) != k or buf[0].shape[0] != n or buf[0].dtype != dtype:
        buf = tuple(np.empty(n, dtype=dtype) for _ in range(k))
        setattr(owner, name, buf)
    return buf


class ParticleState:
    """Positions, velocities, density, mass, kind and original id of every particle; in two
    (x, y; u, v) or three dimensions (with ``z``, ``w``: then also ``az``)."""

    def __init__(self, x, y, u, v, rho, m, kind, id=None, extra=None, z=None, w=None):
        n = len(x)
        if (z is None) != (w is None):
            raise ValueError("a three-dimensional state needs both z and w")
        #: 2 or 3
        self.dim = 2 if z is None else 3
        #: the persistent float arrays of this state's dimension
        self.persistent_f8 = PERSISTENT_F8 if self.dim == 2 else \
            ("x", "y", "z", "u", "v", "w", "rho", "m")
        self.working = WORKING if self.dim == 2 else ("u", "v", "w", "rho", "m")
        self.scratch = SCRATCH if self.dim == 2 else SCRATCH + ("az",)
        #: further persistent float fields (e.g. an integrator's previous step), permuted,
        #: written to and read from time directories like the others
        self.extra: dict[str, np.ndarray] = {
            k: np.ascontiguousarray(a, dtype=np.float64) for k, a in (extra or {}).items()}
        self.x = np.ascontiguousarray(x, dtype=np.float64)
        self.y = np.ascontiguousarray(y, dtype=np.float64)
        self.u = np.ascontiguousarray(u, dtype=np.float64)
        self.v = np.ascontiguousarray(v, dtype=np.float64)
        if self.dim == 3:
            self.z = np.ascontiguousarray(z, dtype=np.float64)
            self.w = np.ascontiguousarray(w, dtype=np.float64)
        self.rho = np.ascontiguousarray(rho, dtype=np.float64)
        self.m = np.ascontiguousarray(m, dtype=np.float64)
        self.kind = np.ascontiguousarray(kind, dtype=np.int64)
        self.id = np.ascontiguousarray(np.arange(n) if id is None else id, dtype=np.int64)
        for name in self.persistent_f8 + PERSISTENT_I8:
            if getattr(self, name).shape != (n,):
                raise ValueError(f"particle field {name!r} has shape "
                                 f"{getattr(self, name).shape}, expected ({n},)")
        #: the working precision of velocities, density, mass and the scratch arrays
        self.dtype = np.dtype(np.float64)
        self._alloc_scratch()

    @property
    def positions(self) -> tuple:
        """(x, y) or (x, y, z)."""
        return (self.x, self.y) if self.dim == 2 else (self.x, self.y, self.z)

    @property
    def velocities(self) -> tuple:
        """(u, v) or (u, v, w)."""
        return (self.u, self.v) if self.dim == 2 else (self.u, self.v, self.w)

    @property
    def accelerations(self) -> tuple:
        """(ax, ay) or (ax, ay, az): dv/dt of the last evaluation."""
        return (self.ax, self.ay) if self.dim == 2 else (self.ax, self.ay, self.az)

    def set_precision(self, dtype) -> None:
        """Hold velocities, density, mass and the scratch arrays in ``dtype`` (float64 or
        float32); positions stay float64."""
        self.dtype = np.dtype(dtype)
        for name in self.working:
            setattr(self, name, np.ascontiguousarray(getattr(self, name), dtype=self.dtype))
        self._alloc_scratch()

    def _alloc_scratch(self):
        n = self.n
        for name in self.scratch:
            setattr(self, name, np.zeros(n, dtype=self.dtype))

    @property
    def n(self) -> int:
        return self.x.shape[0]

    @property
    def n_fluid(self) -> int:
        return int(np.count_nonzero(self.kind == FLUID))

    def apply(self, order: np.ndarray, permute):
        """Reorder every persistent array by ``order`` (one numba pass, no Python loops)."""
        extra = list(self.extra)
        f8_names = [n for n in self.persistent_f8 if getattr(self, n).dtype == np.float64]
        f4_names = [n for n in self.persistent_f8 if n not in f8_names]
        f8 = np.stack([getattr(self, n) for n in f8_names] + [self.extra[k] for k in extra])
        i8 = np.stack([getattr(self, n) for n in PERSISTENT_I8])
        out_f, out_i = permute(order, f8, i8)
        for k, name in enumerate(extra):
            self.extra[name] = out_f[len(f8_names) + k]
        for k, name in enumerate(f8_names):
            setattr(self, name, out_f[k])
        for k, name in enumerate(PERSISTENT_I8):
            setattr(self, name, out_i[k])
        if f4_names:
            out_4, _ = permute(order, np.stack([getattr(self, n) for n in f4_names]),
                               np.empty((0, order.shape[0]), dtype=np.int64))
            for k, name in enumerate(f4_names):
                setattr(self, name, out_4[k])

    def keep(self, mask: np.ndarray):
        """Drop the particles where ``mask`` is False."""
        for name in self.persistent_f8 + PERSISTENT_I8:
            setattr(self, name, np.ascontiguousarray(getattr(self, name)[mask]))
        for name in self.extra:
            self.extra[name] = np.ascontiguousarray(self.extra[name][mask])
        self._alloc_scratch()

    def append(self, x, y, u, v, rho, m, kind, id, z=None, w=None):
        """Add particles at the end (extra fields get zeros); a 3-D state also takes their
        ``z`` and ``w``."""
        if (self.dim == 3) != (z is not None and w is not None):
            raise ValueError(f"append: a {self.dim}-D state takes "
                             f"{'z and w' if self.dim == 3 else 'no z, w'}")
        k = len(x)
        given = dict(x=x, y=y, z=z, u=u, v=v, w=w, rho=rho, m=m, kind=kind, id=id)
        for name in self.persistent_f8 + PERSISTENT_I8:
            new = given[name]
            old = getattr(self, name)
            setattr(self, name, np.ascontiguousarray(np.concatenate(
                [old, np.asarray(new, dtype=old.dtype)])))
        for name in self.extra:
            self.extra[name] = np.concatenate([self.extra[name], np.zeros(k)])
        self._alloc_scratch()

    # --- time-directory fields -----------------------------------------------------------
    def to_fields(self, p=None) -> dict[str, np.ndarray]:
        """The fields of a time directory (ghost particles left out)."""
        real = self.kind != GHOST
        sel = slice(None) if real.all() else real
        out = {
            "positions": np.column_stack([a[sel] for a in self.positions]),
            "U": np.column_stack([a[sel] for a in self.velocities]).astype(np.float64,
                                                                           copy=False),
            "rho": self.rho[sel].astype(np.float64),
            "mass": self.m[sel].astype(np.float64),
            "type": self.kind[sel].copy(),
            "origId": self.id[sel].copy(),
        }
        if p is not None:
            out["p"] = np.asarray(p, dtype=np.float64)[sel].copy()
        for k, a in self.extra.items():
            out[k] = a[sel].copy()
        return out

    @classmethod
    def from_fields(cls, f: dict[str, np.ndarray]) -> "ParticleState":
        missing = [k for k in ("positions", "U", "rho", "mass", "type") if k not in f]
        if missing:
            raise KeyError(f"missing particle field(s): {', '.join(missing)}")
        pos, vel = f["positions"], f["U"]
        known = {"positions", "U", "rho", "mass", "type", "origId", "p"}
        extra = {k: a for k, a in f.items() if k not in known and a.ndim == 1
                 and a.dtype.kind == "f"}
        three = pos.shape[1] == 3 and vel.shape[1] == 3
        return cls(pos[:, 0], pos[:, 1], vel[:, 0], vel[:, 1], f["rho"], f["mass"], f["type"],
                   f.get("origId"), extra, z=pos[:, 2] if three else None,
                   w=vel[:, 2] if three else None)
