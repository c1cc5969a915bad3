"""The CPU backend's runner of an integrator's particle updates (:mod:`sphfoam.engine.stepping`).

:class:`ParticleUpdates` compiles the updates the integrator declares
(:func:`sphfoam.engine.build.build_updates`), holds the arrays it keeps through a step and
calls each update with the arrays it names: the state's, the advection velocity, the kept
arrays, the persistent fields of its history.
"""

from __future__ import annotations

import numpy as np

from sphfoam.engine.stepping import components, field_components

#: the contract's state arrays by their names in expanded code
_STATE = {"x": "x", "y": "y", "z": "z", "u": "u", "v": "v", "w": "w", "rho": "rho",
          "drho": "drho", "kind": "kind", "ax": "ax", "ay": "ay", "az": "az"}


class ParticleUpdates:
    """The compiled particle updates of one integrator, run on the host's arrays."""

    def __init__(self, integrator, dim: int = 2):
        from sphfoam.engine.build import build_updates

        self.integrator = integrator
        self.dim = dim
        self.module = build_updates(integrator, dim)
        self._updates = {u.name: u for u in integrator.updates}
        #: kept array (expanded name) -> (its group, index in the group, precision)
        self._kept: dict[str, tuple[str, int, str]] = {}
        for name, precision in getattr(integrator, "kept", {}).items():
            for i, c in enumerate(components(name, dim)):
                self._kept[c] = (name, i, precision)
        #: history array (expanded name) -> persistent field of the state (state.extra)
        self._history: dict[str, str] = {}
        for name, template in getattr(integrator, "history", {}).items():
            self._history.update(zip(components(name, dim), field_components(template, dim)))
        self._advection = components("pU@", dim)
        #: the kept arrays by group (``kept``), made anew only when n or the dtype changed
        self._buffers: dict[str, tuple] = {}
        for upd in integrator.updates:
            for a in self.module.ARRAYS[upd.name]:
                if not (a in _STATE or a in self._kept or a in self._history
                        or a in self._advection):
                    raise ValueError(f"integrator {integrator.name!r}, update {upd.name!r}: "
                                     f"unknown array {a!r}")

    def run(self, name: str, state, advection, scalars: dict) -> None:
        """Update ``name`` for every particle of ``state``; ``advection`` is the velocity
        positions move with (one array per component)."""
        upd = self._updates[name]
        args = [self._array(a, state, advection) for a in self.module.ARRAYS[name]]
        args += [scalars[s] for s in upd.scalars]
        getattr(self.module, f"update_{name}")(*args)

    def _array(self, a: str, state, advection):
        if a in _STATE:
            return getattr(state, _STATE[a])
        if a in self._kept:
            group, i, precision = self._kept[a]
            dtype = state.dtype if precision == "working" else np.float64
            buf = self._buffers.get(group)
            if buf is None or buf[0].shape[0] != state.n or buf[0].dtype != dtype:
                buf = tuple(np.empty(state.n, dtype=dtype)
                            for _ in components(group, self.dim))
                self._buffers[group] = buf
            return buf[i]
        if a in self._history:
            return state.extra[self._history[a]]
        return advection[self._advection.index(a)]
