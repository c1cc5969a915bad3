"""The kernels of the mirror ghosts' device form (sphfoam.models.mirror_cuda) against the
CPU's loops (sphfoam.models.mirror) on made-up particles near two moving walls that meet in
a corner: the count and table of ghosts, their state (free slip and no-slip, p_G = p_a and
hydrostatic), their activity, the push-back and the wall shear of each law, in double
precision and (``*_single``) with velocity, density and mass in single. Prints one JSON
line, ``RESULT {...}``: per check the largest relative difference (0 for integers that
agree, inf for those that do not). Run by tests/test_cuda_backend.py under
NUMBA_ENABLE_CUDASIM=1.
"""

from __future__ import annotations

import json

import numpy as np


def _rel(a, b) -> float:
    a, b = np.asarray(a, dtype=np.float64), np.asarray(b, dtype=np.float64)
    if a.shape != b.shape:
        return float("inf")
    scale = max(float(np.max(np.abs(a))) if a.size else 0.0, 1e-300)
    return float(np.max(np.abs(a - b))) / scale if a.size else 0.0


def _same(a, b) -> float:
    return 0.0 if np.array_equal(np.asarray(a), np.asarray(b)) else float("inf")


def main(working=np.float64) -> dict:
    """The checks with velocity, density and mass in the precision ``working``."""
    from numba import cuda

    from sphfoam.models import mirror_cuda as dm
    from sphfoam.engine.cuda.device import THREADS, blocks
    from sphfoam.models import mirror as gh

    def launch(kernel, n, *args):
        kernel[blocks(n), THREADS](*args)

    rng = np.random.default_rng(7)
    # the bed y = 0 (moving along x) and the wall x = 0 (moving along x and y), a corner
    seg = np.array([[0.0, 0.0, 1.0, 0.0, 0.0, 1.0, 1.0, 0.1, 0.0],
                    [0.0, 1.0, 0.0, -1.0, 1.0, 0.0, 1.0, 0.2, 0.05]])
    corners = np.array([[0, 1]], dtype=np.int64)
    reach, margin = 0.1, 0.02
    n = 160
    x = rng.uniform(-0.03, 0.5, n)
    y = rng.uniform(-0.03, 0.5, n)
    u = rng.normal(0.0, 0.5, n).astype(working)
    v = rng.normal(0.0, 0.5, n).astype(working)
    rho = (1000.0 + rng.normal(0.0, 5.0, n)).astype(working)
    m = (1.0 + rng.uniform(0.0, 0.1, n)).astype(working)
    kind = np.where(rng.uniform(size=n) < 0.1, 1, 0).astype(np.int64)
    out = {}

    # count and fill, T(3.77)
    count = np.zeros(n, dtype=np.int64)
    gh.count_ghosts(x, y, kind, seg, corners, reach, count, margin)
    offset = np.zeros(n + 1, dtype=np.int64)
    np.cumsum(count, out=offset[1:])
    ng = int(offset[n])
    src, s1, s2 = (np.empty(ng, dtype=np.int64) for _ in range(3))
    gh.fill_ghosts(x, y, kind, seg, corners, reach, offset, src, s1, s2, margin)
    cell = np.zeros(n, dtype=np.int64)
    d_count = cuda.device_array(n, dtype=np.int64)
    launch(dm.count_ghosts, n, x, y, kind, cell, 99, seg, corners, reach, margin, d_count)
    out["count"] = _same(count, d_count.copy_to_host())
    table = [np.full(n + ng, -1, dtype=np.int64) for _ in range(3)]
    launch(dm.fill_ghosts, n, x, y, kind, cell, 99, seg, corners, reach, margin, n, offset,
           *table)
    out["table"] = max(_same(t[n:], c) for t, c in zip(table, (src, s1, s2)))
    out["ghosts"] = ng
    out["corner_ghosts"] = int((s2 >= 0).sum())

    # the ghosts' state: free slip and no-slip, p_G = p_a and hydrostatic
    active = rng.uniform(size=ng) < 0.8
    gidx = np.arange(n, n + ng)
    out["state"] = 0.0
    for no_slip in (False, True):
        for hydro in ((False, 0.0, 0.0, 1.0, 1.0, 1.0),
                      (True, 0.0, -9.81, 1000.0, 2.5e5, 7.0)):
            cpu = [np.concatenate([a, np.zeros(ng, dtype=a.dtype)])
                   for a in (x, y, u, v, rho, m)]
            dev = [a.copy() for a in cpu]
            gh.refresh_ghosts(*cpu, gidx, src, s1, s2, seg, no_slip, active, *hydro)
            gact = np.concatenate([np.zeros(n), active]).astype(np.uint8)
            launch(dm.refresh_ghosts, n + ng, *dev, table[0], table[1], table[2], seg,
                   no_slip, gact, *hydro)
            out["state"] = max(out["state"], *(_rel(a, b) for a, b in zip(cpu, dev)))

    # activity, the criterion of T(3.77) within the support (no skin)
    act = np.empty(ng, dtype=np.bool_)
    n_on = gh.ghost_activity(x, y, src, s1, s2, seg, 0.8 * reach, act)
    xe, ye = np.concatenate([x, np.zeros(ng)]), np.concatenate([y, np.zeros(ng)])
    d_act = np.zeros(n + ng, dtype=np.uint8)
    counts = np.zeros(3, dtype=np.int64)
    launch(dm.ghost_activity, n + ng, xe, ye, table[0], table[1], table[2], seg,
           0.8 * reach, d_act, counts)
    out["activity"] = max(_same(act, d_act[n:].astype(np.bool_)),
                          0.0 if counts[0] == n_on else float("inf"))
    out["dormant"] = int(ng - n_on)

    # the push-back across a wall
    cpu = [a.copy() for a in (x, y, u, v)]
    dev = [a.copy() for a in (x, y, u, v)]
    pushed = gh.push_back(*cpu, kind, seg, reach)
    total = np.zeros(1, dtype=np.int64)
    launch(dm.push_back, n, *dev, kind, seg, reach, total)
    out["push_back"] = max(max(_rel(a, b) for a, b in zip(cpu, dev)),
                           0.0 if total[0] == pushed else float("inf"))
    out["pushed"] = int(pushed)

    # the wall shear of each law of the wall
    phi = np.linspace(1.0, 0.0, 33) ** 2
    out["shear"] = 0.0
    for law, coef in ((0, 1e-6), (1, 1e-3), (2, 20.0)):
        ax = rng.normal(0.0, 1.0, n).astype(working)
        ay = rng.normal(0.0, 1.0, n).astype(working)
        cpu = [ax.copy(), ay.copy()]
        dev = [ax.copy(), ay.copy()]
        out[f"sheared_{law}"] = int(gh.wall_shear(x, y, u, v, kind, seg, reach, phi, law,
                                                  coef, *cpu))
        launch(dm.wall_shear, n, x, y, u, v, kind, seg, reach, phi, law, coef, *dev)
        out["shear"] = max(out["shear"], *(_rel(a - ax, b - ax) for a, b in zip(cpu, dev)))
    return out


def report(check, single_keys) -> None:
    """Print ``RESULT {...}``: ``check()`` in double precision, with ``single_keys`` of
    ``check(np.float32)`` added as ``*_single`` (an exception as one line)."""
    try:
        res = check()
        single = check(np.float32)
        res.update({f"{k}_single": single[k] for k in single_keys})
    except Exception as e:  # noqa: BLE001  (reported as one line: the test reads it)
        res = {"error": f"{type(e).__name__}: {e}"}
    print("RESULT " + json.dumps(res), flush=True)


if __name__ == "__main__":
    report(main, ("state", "push_back", "shear"))
