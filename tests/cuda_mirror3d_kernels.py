"""The 3-D kernels of the mirror ghosts' device form (sphfoam.models.mirror_cuda, ``*3``)
against the CPU's loops (sphfoam.models.mirror3d) on made-up particles in the corner of a box
tank whose faces move (the floor z = 0, the walls x = 0 and y = 0, each face its own
velocity): the count and table of ghosts (face, edge and vertex ghosts), their state (free
slip and no-slip, p_G = p_a and hydrostatic), their activity, the ghosts a build would make,
the dormant ones' fluid neighbours and the push-back of particles that crossed a face, in
double precision and (``*_single``) with velocity, density and mass in single. Prints one
JSON line, ``RESULT {...}``: per check the largest relative difference (0 for integers that
agree, inf for those that do not). Run by tests/test_cuda_backend.py under
NUMBA_ENABLE_CUDASIM=1.
"""

from __future__ import annotations

import numpy as np

from cuda_mirror_kernels import _rel, _same       # this folder: the 2-D kernels' check


def main(working=np.float64) -> dict:
    """The checks with velocity, density and mass in the precision ``working``."""
    from numba import cuda

    from sphfoam.case.geometry import Plane
    from sphfoam.engine.cuda.device import THREADS, blocks
    from sphfoam.models import mirror3d as m3
    from sphfoam.models import mirror_cuda as dm

    def launch(kernel, n, *args):
        kernel[blocks(n), THREADS](*args)

    rng = np.random.default_rng(11)
    faces = [Plane(2, 0.0, 1.0, (0.0, 1.0, 0.0, 1.0), (0.1, 0.0, 0.0), 0),     # floor
             Plane(0, 0.0, 1.0, (0.0, 1.0, 0.0, 1.0), (0.05, 0.2, 0.0), 0),    # x = 0
             Plane(1, 0.0, 1.0, (0.0, 1.0, 0.0, 1.0), (0.0, -0.1, 0.03), 0)]   # y = 0
    pl = m3.plane_array(faces)
    reach, margin = 0.1, 0.02
    n = 400
    x, y, z = (rng.uniform(-0.03, 0.4, n) for _ in range(3))
    u, v, w = (rng.normal(0.0, 0.5, n).astype(working) for _ in range(3))
    rho = (1000.0 + rng.normal(0.0, 5.0, n)).astype(working)
    m = (1.0 + rng.uniform(0.0, 0.1, n)).astype(working)
    kind = np.where(rng.uniform(size=n) < 0.1, 1, 0).astype(np.int64)
    out = {}

    # count and fill, T(3.77): a face, an edge (3), a vertex (7)
    count = np.zeros(n, dtype=np.int64)
    m3.count_ghosts(x, y, z, kind, pl, reach, count, margin)
    offset = np.zeros(n + 1, dtype=np.int64)
    np.cumsum(count, out=offset[1:])
    ng = int(offset[n])
    src, f1, f2, f3 = (np.empty(ng, dtype=np.int64) for _ in range(4))
    m3.fill_ghosts(x, y, z, kind, pl, reach, offset, src, f1, f2, f3, margin)
    cell = np.zeros(n, dtype=np.int64)
    d_count = np.empty(n, dtype=np.int64)
    launch(dm.count_ghosts3, n, x, y, z, kind, cell, 99, pl, reach, margin, d_count)
    out["count"] = _same(count, d_count)
    table = [np.full(n + ng, -1, dtype=np.int64) for _ in range(4)]
    launch(dm.fill_ghosts3, n, x, y, z, kind, cell, 99, pl, reach, margin, n, offset,
           *table)
    out["table"] = max(_same(t[n:], c) for t, c in zip(table, (src, f1, f2, f3)))
    out["ghosts"] = ng
    out["edge_ghosts"] = int(((f2 >= 0) & (f3 < 0)).sum())
    out["vertex_ghosts"] = int((f3 >= 0).sum())

    # the ghosts' state: free slip and no-slip, p_G = p_a and hydrostatic
    active = rng.uniform(size=ng) < 0.8
    gidx = np.arange(n, n + ng)
    out["state"] = 0.0
    for no_slip in (False, True):
        for hydro in ((False, 0.0, 0.0, 0.0, 1.0, 1.0, 1.0),
                      (True, 0.0, 0.0, -9.81, 1000.0, 2.5e5, 7.0)):
            cpu = [np.concatenate([a, np.zeros(ng, dtype=a.dtype)])
                   for a in (x, y, z, u, v, w, rho, m)]
            dev = [a.copy() for a in cpu]
            m3.refresh_ghosts(*cpu, gidx, src, f1, f2, f3, pl, no_slip, active, *hydro)
            gact = np.concatenate([np.zeros(n), active]).astype(np.uint8)
            launch(dm.refresh_ghosts3, n + ng, *dev, *table, pl, no_slip, gact, *hydro)
            out["state"] = max(out["state"], *(_rel(a, b) for a, b in zip(cpu, dev)))

    # activity, the criterion of T(3.77) within the support (no skin); the ghosts a build
    # would make now; the dormant ghosts' fluid neighbours within the support
    act = np.empty(ng, dtype=np.bool_)
    n_on = m3.ghost_activity(x, y, z, src, f1, f2, f3, pl, 0.8 * reach, act)
    xe, ye, ze = (np.concatenate([a, np.zeros(ng)]) for a in (x, y, z))
    d_act = np.zeros(n + ng, dtype=np.uint8)
    counts = np.zeros(3, dtype=np.int64)
    launch(dm.ghost_activity3, n + ng, xe, ye, ze, *table, pl, 0.8 * reach, d_act, counts)
    made = np.zeros(n, dtype=np.int64)
    m3.count_ghosts(x, y, z, kind, pl, 0.8 * reach, made)
    launch(dm.count_qualifying3, n, x, y, z, kind, pl, 0.8 * reach, counts)
    out["activity"] = max(_same(act, d_act[n:].astype(np.bool_)),
                          0.0 if counts[0] == n_on else float("inf"),
                          0.0 if counts[1] == made.sum() else float("inf"))
    out["dormant"] = int(ng - n_on)
    # every ghost's neighbours: every particle (the CPU counts the fluid ones in reach)
    cpu = [np.concatenate([a, np.zeros(ng)]) for a in (x, y, z)]
    m3.refresh_ghosts(*cpu, *(np.zeros(n + ng) for _ in range(5)), gidx, src, f1, f2, f3,
                      pl, False, act)
    ke = np.concatenate([kind, np.full(ng, 2)])
    nb_start = np.zeros(n + ng + 1, dtype=np.int64)
    nb_start[n + 1:] = n * np.arange(1, ng + 1)
    nb_idx = np.tile(np.arange(n, dtype=np.uint32), ng)
    gsrc = np.concatenate([np.full(n, -1), src])
    near = 0
    for j in np.flatnonzero(~act):
        near += m3.fluid_within(n + j, *cpu, ke, nb_start, nb_idx, reach ** 2)
    launch(dm.dormant_near_fluid3, n + ng, *cpu, ke, gsrc, d_act, nb_start, nb_idx,
           reach ** 2, counts)
    out["dormant_near"] = 0.0 if counts[2] == near else float("inf")
    out["dormant_near_count"] = int(near)

    # the push-back across a face
    cpu = [a.copy() for a in (x, y, z, u, v, w)]
    dev = [a.copy() for a in (x, y, z, u, v, w)]
    pushed = m3.push_back(*cpu, kind, pl, reach)
    total = np.zeros(1, dtype=np.int64)
    launch(dm.push_back3, n, *dev, kind, pl, reach, total)
    out["push_back"] = max(max(_rel(a, b) for a, b in zip(cpu, dev)),
                           0.0 if total[0] == pushed else float("inf"))
    out["pushed"] = int(pushed)
    return out


if __name__ == "__main__":
    from cuda_mirror_kernels import report

    report(main, ("state", "push_back"))
