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
SCRATCH = ("p", "c", "ax", "ay", "drho", "sigma", "u_half", "v_half")


class ParticleState:
    """Positions, velocities, density, mass, kind and original id of every particle."""

    def __init__(self, x, y, u, v, rho, m, kind, id=None, extra=None):
        n = len(x)
        #: further persistent float fields (e.g. an integrator's previous step), permuted,
        #: written to and read from time directories like the others
        self.extra: dict[str, np.ndarray] = {
            k: np.ascontiguousarray(a, dtype=np.float64) for k, a in (extra or {}).items()}
        self.x = np.ascontiguousarray(x, dtype=np.float64)
        self.y = np.ascontiguousarray(y, dtype=np.float64)
        self.u = np.ascontiguousarray(u, dtype=np.float64)
        self.v = np.ascontiguousarray(v, dtype=np.float64)
        self.rho = np.ascontiguousarray(rho, dtype=np.float64)
        self.m = np.ascontiguousarray(m, dtype=np.float64)
        self.kind = np.ascontiguousarray(kind, dtype=np.int64)
        self.id = np.ascontiguousarray(np.arange(n) if id is None else id, dtype=np.int64)
        for name in PERSISTENT_F8 + PERSISTENT_I8:
            if getattr(self, name).shape != (n,):
                raise ValueError(f"particle field {name!r} has shape "
                                 f"{getattr(self, name).shape}, expected ({n},)")
        self._alloc_scratch()

    def _alloc_scratch(self):
        n = self.n
        for name in SCRATCH:
            setattr(self, name, np.zeros(n))

    @property
    def n(self) -> int:
        return self.x.shape[0]

    @property
    def n_fluid(self) -> int:
        return int(np.count_nonzero(self.kind == FLUID))

    def apply(self, order: np.ndarray, permute):
        """Reorder every persistent array by ``order`` (one numba pass, no Python loops)."""
        extra = list(self.extra)
        f8 = np.stack([getattr(self, n) for n in PERSISTENT_F8] + [self.extra[k] for k in extra])
        i8 = np.stack([getattr(self, n) for n in PERSISTENT_I8])
        out_f, out_i = permute(order, f8, i8)
        for k, name in enumerate(extra):
            self.extra[name] = out_f[len(PERSISTENT_F8) + k]
        for k, name in enumerate(PERSISTENT_F8):
            setattr(self, name, out_f[k])
        for k, name in enumerate(PERSISTENT_I8):
            setattr(self, name, out_i[k])

    def keep(self, mask: np.ndarray):
        """Drop the particles where ``mask`` is False."""
        for name in PERSISTENT_F8 + PERSISTENT_I8:
            setattr(self, name, np.ascontiguousarray(getattr(self, name)[mask]))
        for name in self.extra:
            self.extra[name] = np.ascontiguousarray(self.extra[name][mask])
        self._alloc_scratch()

    def append(self, x, y, u, v, rho, m, kind, id):
        """Add particles at the end (extra fields get zeros)."""
        k = len(x)
        for name, new in zip(PERSISTENT_F8 + PERSISTENT_I8, (x, y, u, v, rho, m, kind, id)):
            setattr(self, name, np.ascontiguousarray(np.concatenate([getattr(self, name), new])))
        for name in self.extra:
            self.extra[name] = np.concatenate([self.extra[name], np.zeros(k)])
        self._alloc_scratch()

    # --- time-directory fields -----------------------------------------------------------
    def to_fields(self, p=None) -> dict[str, np.ndarray]:
        """The fields of a time directory (ghost particles left out)."""
        real = self.kind != GHOST
        sel = slice(None) if real.all() else real
        out = {
            "positions": np.column_stack([self.x[sel], self.y[sel]]),
            "U": np.column_stack([self.u[sel], self.v[sel]]),
            "rho": self.rho[sel].copy(),
            "mass": self.m[sel].copy(),
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
        return cls(pos[:, 0], pos[:, 1], vel[:, 0], vel[:, 1], f["rho"], f["mass"], f["type"],
                   f.get("origId"), extra)
