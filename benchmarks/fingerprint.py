"""Fields after N steps of every tutorial and of model variants, for before/after comparisons.

    python benchmarks/fingerprint.py save  OUT.npz [--steps N]
    python benchmarks/fingerprint.py compare A.npz B.npz

``save`` clones each tutorial (and a dam-break per boundary, filter, correction, viscosity,
turbulence and integrator variant) into a temporary folder, sets it up, runs N steps with the
case's own models and stores x, y, u, v, rho (z and w too in 3-D; sorted by particle id)
and the time reached.
``compare`` prints, per case, whether the fields are bitwise equal and the largest relative
difference otherwise (of a velocity component, against the velocity's largest component). A refactoring of the engine should give ``bitwise`` everywhere, or
round-off where the order of a sum legitimately changed.
"""

from __future__ import annotations

import argparse
import sys
import tempfile
from pathlib import Path

import numpy as np

from bench_engine import THESIS_FLUME

ROOT = Path(__file__).resolve().parent.parent
TUT = ROOT / "tutorials"
SPH = "constant/sphProperties"
DB = "damBreak"

#: name -> (tutorial, edits)
CASES: dict[str, tuple[str, dict]] = {
    "damBreak": (DB, {}),
    "hydrostaticTank": ("hydrostaticTank", {}),
    "poiseuille": ("poiseuille", {}),
    "couette": ("couette", {}),
    "turbulentChannel": ("turbulentChannel", {}),
    "wavePaddle": ("wavePaddle", {}),
    # the thesis's optimum flume (the tutorial's default until issue 35's best default)
    "solitaryWave": ("solitaryWave", THESIS_FLUME),
    # the tutorial as it is: Fourtakas's delta-SPH, delta+ shifting R 0.05, the exact
    # wave's paddle
    "solitaryWaveDefault": ("solitaryWave", {}),
    "solitaryWallRunup": ("solitaryWallRunup", {}),
    "solitaryCollision": ("solitaryCollision", {}),
    # P's set-up of the collision (KdV2 waves, P's bed: its default until issue 35's study)
    "collisionP": ("solitaryCollision", {
        "constant/waveProperties:waves.right.theory": "kdv2",
        "constant/waveProperties:waves.left.theory": "kdv2",
        f"{SPH}:boundary.pressure": "mirror"}),
    # P's set-up of the wall case (its default until issue 35's study; tests/conftest.P_WALL)
    "wallRunupP": ("solitaryWallRunup", {
        f"{SPH}:kernel": {"type": "gaussian", "hdx": 1.3333333},
        f"{SPH}:velocityCorrection": {"type": "xsph", "epsilon": 0.5},
        f"{SPH}:densityFilter": {"type": "mlsReinitialisation", "every": 20},
        f"{SPH}:particleShifting": {"type": "none"},
        f"{SPH}:boundary.pressure": "mirror",
        "constant/waveProperties:waves.incident.theory": "kdv2",
        "system/sphSchemes:integrator": {"type": "predictorCorrector"}}),
    "db_repulsiveMK": (DB, {f"{SPH}:boundary": {"type": "repulsiveMonaghanKos"}}),
    "db_repulsiveMK_slip": (DB, {f"{SPH}:boundary": {"type": "repulsiveMonaghanKos",
                                                    "noSlip": False}}),
    "db_repulsive2003": (DB, {f"{SPH}:boundary": {"type": "repulsiveMonaghan2003"}}),
    "db_hybrid": (DB, {f"{SPH}:boundary": {"type": "hybrid"}}),
    "db_adami": (DB, {f"{SPH}:boundary": {"type": "adami"}}),
    "db_adami_slip": (DB, {f"{SPH}:boundary": {"type": "adami", "noSlip": False}}),
    "db_mirror": (DB, {f"{SPH}:boundary": {"type": "mirrorGhosts", "noSlip": True}}),
    "db_shepard": (DB, {f"{SPH}:densityFilter": {"type": "shepard", "every": 5}}),
    "db_mls": (DB, {f"{SPH}:densityFilter": {"type": "mlsReinitialisation", "every": 5}}),
    "db_delta": (DB, {f"{SPH}:densityFilter": {"type": "deltaSPH"}}),
    "db_xsph": (DB, {f"{SPH}:velocityCorrection": {"type": "xsph"}}),
    "db_csph": (DB, {f"{SPH}:kernelCorrection": {"type": "cspH"}}),
    "db_csph_a": (DB, {f"{SPH}:kernelCorrection": {"type": "cspH", "symmetric": False}}),
    "db_ivisc": (DB, {f"{SPH}:viscosity": {"type": "improvedArtificial"}}),
    "db_ivisc_bals": (DB, {f"{SPH}:viscosity": {"type": "improvedArtificial",
                                               "switch": "balsara"}}),
    "db_laminar_sps": (DB, {f"{SPH}:viscosity": {"type": "laminar"},
                            f"{SPH}:turbulence": {"type": "smagorinskySPS"}}),
    "db_cl_dw": (DB, {f"{SPH}:momentum": {"type": "colagrossiLandrini"},
                      f"{SPH}:continuity": {"type": "densityWeighted"}}),
    "db_wendland": (DB, {f"{SPH}:kernel": {"type": "wendlandC2"}}),
    "db_gauss": (DB, {f"{SPH}:kernel": {"type": "gaussian", "hdx": 1.33}}),
    "db_cubic": (DB, {f"{SPH}:kernel": {"type": "cubicSpline"}}),
    "db_quintic": (DB, {f"{SPH}:kernel": {"type": "quintic"}}),
    "db_verlet": (DB, {"system/sphSchemes:integrator": {"type": "verlet", "everyN": 4},
                       f"{SPH}:densityFilter": {"type": "shepard", "every": 7}}),
    "db_symplectic": (DB, {"system/sphSchemes:integrator": {"type": "symplectic"},
                           f"{SPH}:velocityCorrection": {"type": "xsph"}}),
    "db_pc": (DB, {"system/sphSchemes:integrator": {"type": "predictorCorrector"},
                   f"{SPH}:velocityCorrection": {"type": "xsph"}}),
    # issue 13's low-dissipation models
    "db_fourtakas": (DB, {f"{SPH}:densityFilter": {"type": "fourtakasDeltaSPH"}}),
    "db_fourtakas_particle": (DB, {f"{SPH}:densityFilter": {"type": "fourtakasDeltaSPH",
                                                            "reference": "particle"}}),
    "db_antuono": (DB, {f"{SPH}:densityFilter": {"type": "antuonoDeltaSPH"}}),
    "db_dplus": (DB, {f"{SPH}:densityFilter": {"type": "fourtakasDeltaSPH"},
                      f"{SPH}:particleShifting": {"type": "deltaPlusShifting"}}),
    "db_lind": (DB, {f"{SPH}:particleShifting": {"type": "lindShifting"}}),
    # issue 35: the shift carrying mass and density (the ALE mass flux)
    "db_dplus_mass": (DB, {f"{SPH}:densityFilter": {"type": "fourtakasDeltaSPH"},
                           f"{SPH}:particleShifting": {"type": "deltaPlusShifting",
                                                      "correctDensity": True,
                                                      "correctMass": True}}),
    "db_hybrid_xsph_mls": (DB, {f"{SPH}:boundary": {"type": "hybrid"},
                                f"{SPH}:velocityCorrection": {"type": "xsph"},
                                f"{SPH}:densityFilter": {"type": "mlsReinitialisation",
                                                         "every": 4}}),
    # three dimensions, coarse: the tank at rest, SPHERIC's dam break (Fourtakas's delta-SPH,
    # the block), the extruded flume periodic across
    "hydrostaticTank3D": ("hydrostaticTank3D", {}),
    "damBreak3D": ("damBreak3D", {"system/particleDict:dx": 0.055}),
    "solitaryWave3D": ("solitaryWave3D", {"system/particleDict:dx": 0.05}),
}


def _edit(case: Path, edits: dict) -> None:
    from sphfoam.case.edit import set_entry

    for where, value in edits.items():
        rel, key = where.split(":")
        set_entry(case, rel, key, value)


def run_case(name: str, steps: int, tmp: Path) -> dict[str, np.ndarray]:
    import shutil

    from sphfoam.case.case import Case
    from sphfoam.case.edit import clone_case
    from sphfoam.engine.state import GHOST, ParticleState
    from sphfoam.io.fields import read_state
    from sphfoam.assemble import build_simulation
    from sphfoam.setup import setup_case

    tut, edits = CASES[name]
    case_dir = clone_case(TUT / tut, tmp / name)
    _edit(case_dir, edits)
    case = Case(case_dir)
    setup_case(case, log=lambda *_: None)
    state = ParticleState.from_fields(read_state(case_dir / "0"))
    sim = build_simulation(case, state)
    for _ in range(steps):
        sim.step()
    st = sim.state
    real = st.kind != GHOST
    order = np.argsort(st.id[real], kind="stable")
    fields = ("x", "y", "z", "u", "v", "w", "rho") if st.dim == 3 else ("x", "y", "u", "v", "rho")
    out = {k: getattr(st, k)[real][order].copy() for k in fields}
    out["time"] = np.array([sim.time])
    shutil.rmtree(case_dir, ignore_errors=True)
    return out


def save(path: Path, steps: int, only: list[str] | None) -> None:
    data = {}
    with tempfile.TemporaryDirectory() as tmp:
        for name in CASES:
            if only and name not in only:
                continue
            try:
                res = run_case(name, steps, Path(tmp))
            except Exception as e:  # noqa: BLE001  (recorded, so a comparison shows it)
                print(f"{name}: FAILED {type(e).__name__}: {e}", flush=True)
                continue
            for k, v in res.items():
                data[f"{name}/{k}"] = v
            print(f"{name}: {res['x'].size} particles, t = {res['time'][0]:.6g}", flush=True)
    np.savez(path, **data)


def compare(a: Path, b: Path) -> int:
    A, B = np.load(a), np.load(b)
    names = sorted({k.split("/")[0] for k in A.files} | {k.split("/")[0] for k in B.files})
    worst = 0
    for name in names:
        keys = [k for k in A.files if k.startswith(name + "/")]
        if not keys or not all(k in B.files for k in keys):
            print(f"{name:24s} missing in one of the files")
            worst = max(worst, 2)
            continue
        if any(A[k].shape != B[k].shape for k in keys):
            print(f"{name:24s} different particle counts")
            worst = max(worst, 2)
            continue
        diffs = {}
        for k in keys:
            x, y = A[k], B[k]
            # a velocity component against the velocity's largest component: one that is
            # zero by symmetry (v across a periodic span) holds round-off alone
            field = k.split("/")[1]
            group = [f"{name}/{c}" for c in "uvw" if f"{name}/{c}" in A.files] \
                if field in ("u", "v", "w") else [k]
            scale = max(max(float(np.max(np.abs(A[g]))) for g in group), 1e-300)
            diffs[k.split("/")[1]] = float(np.max(np.abs(x - y))) / scale
        if all(v == 0.0 for v in diffs.values()):
            print(f"{name:24s} bitwise")
        else:
            worst = max(worst, 1)
            print(f"{name:24s} max rel diff " + ", ".join(f"{k} {v:.2e}" for k, v in
                                                          diffs.items()))
    return worst


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    sub = ap.add_subparsers(dest="cmd", required=True)
    s = sub.add_parser("save")
    s.add_argument("out", type=Path)
    s.add_argument("--steps", type=int, default=25)
    s.add_argument("--only", nargs="*")
    c = sub.add_parser("compare")
    c.add_argument("a", type=Path)
    c.add_argument("b", type=Path)
    args = ap.parse_args(argv)
    if args.cmd == "save":
        save(args.out, args.steps, args.only)
        return 0
    return compare(args.a, args.b)


if __name__ == "__main__":
    sys.exit(main())
