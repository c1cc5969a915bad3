"""Fixed-state timings of the pipeline functions of a bench_engine --case case.

    python benchmarks/bench_functions.py CASE [N] [ROUNDS]

The case is built (about N particles) and stepped 30 times; then each pipeline function
(pre-pass, rates, density-only pass, over half lists and gathered; the neighbour list and the
half lists) is called on that same state, three calls a round, ROUNDS rounds, and the median
CPU time of a call printed (one thread)."""
import sys, time, os
sys.path.insert(0, os.path.join(os.getcwd(), "benchmarks"))
import numpy as np, numba
numba.set_num_threads(1)
import bench_engine as be
case = sys.argv[1]; N = int(sys.argv[2]) if len(sys.argv) > 2 else 23000
R = int(sys.argv[3]) if len(sys.argv) > 3 else 15
sim, info = be.make_case_sim(case, N)
for _ in range(30): sim.step()
st = sim.state; p = sim.pipeline
args = sim._grid_args()
fns = {}
if sim._half is not None and p.prepass_half is not None:
    sums = np.empty((p.prepass_sums, st.n), dtype=sim.dtype)
    fns["prepass_half"] = lambda: p.prepass_half(*args, sim._half, sums)
if p.prepass is not None:
    fns["prepass"] = lambda: p.prepass(*args)
if sim._half is not None and p.rates_half is not None:
    fns["rates_half"] = lambda: p.rates_half(*args, sim._half, st.ax, st.ay, st.drho, st.sigma)
    # without sigma, T(3.89): the evaluations an integrator takes no time step from
    fns["rates_half-s"] = lambda: p.rates_half(*args, sim._half, st.ax, st.ay, st.drho,
                                               st.sigma[:0])
fns["rates"] = lambda: p.rates(*args, st.ax, st.ay, st.drho, st.sigma)
if sim._half is not None and p.density_half is not None:
    fns["density_half"] = lambda: p.density_half(*args, sim._half, st.drho)
fns["nlist"] = lambda: p.neighbour_list(st.x, st.y, st.kind, sim.cells, sim.cells.cell_size,
                                        *sim._nb)
if sim._half is not None:
    fns["half_lists"] = lambda: p.half_lists(*sim._nb, sim.cells, sim._half)
if p.step_pass is not None:
    fns["step_pass"] = lambda: p.step_pass(*args)
res = {k: [] for k in fns}
for r in range(R):
    for k, f in fns.items():
        t = time.process_time(); f(); f(); f(); res[k].append((time.process_time() - t) / 3)
print(case, info["n"], "pairs listed", sim._nb[1].shape[0] / st.n)
for k, v in res.items():
    print(f"  {k:14s} {1e3*np.median(v):7.2f} ms")
