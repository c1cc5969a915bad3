"""Every kernel the CUDA backend launches for a case, compiled to PTX for a compute
capability, on a machine with no GPU: what numba's simulator cannot show, that the
generated code is device code.

    python -m sphfoam.cudaptx CASE [CASE ...] [--dx DX] [--cc 9.0] [--edits JSON]
    python -m sphfoam.cudaptx --every-model [--cc 9.0]

Per case (a case directory, or a tutorial's name), in a child process under numba's
simulator (``NUMBA_ENABLE_CUDASIM=1``): the case set up at a coarse ``--dx`` and two steps
of the CUDA backend (and one density filter where the case selects one, one health check
and one kept snapshot, as the time loop makes them), recording each
kernel launched with the numba types of its arguments, as a device launch would type them.
Then, in this process (no simulator, no driver): each recorded kernel compiled with
``numba.cuda.compile_ptx`` for ``--cc`` (default 9.0, the H100/H200). Needs NVIDIA's NVVM
and NVRTC (``pip install "numba-cuda[cu13]"``). Prints one line per
kernel and exits 1 when one fails. ``--every-model``: the dam break at dx 0.1 once per
registered pipeline model (each in place of the tutorial's choice of its family; the
integrators likewise; single precision once), every kernel of each.
"""

from __future__ import annotations

import argparse
import importlib
import importlib.util
import json
import os
import pickle
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def _record(case_src: Path, dx: float | None, out: Path, edits: dict) -> None:
    """(child, under the simulator) Run two steps and pickle the launches:
    [(module name, file, kernel name, argument types, the factory that made it or None)],
    each kernel once per signature."""
    import numba
    from numba.cuda.simulator.kernel import FakeCUDAKernel

    launches: dict = {}
    call = FakeCUDAKernel.__call__

    def recording(self, *args):
        if not self._device:
            fn = self.fn
            sig = tuple(numba.typeof(a) for a in args)
            made_by = getattr(self, "made_by", None)      # a kernel a factory made
            launches[(fn.__module__, fn.__code__.co_filename, fn.__name__, sig,
                      made_by)] = None
        return call(self, *args)

    FakeCUDAKernel.__call__ = recording
    from sphfoam.assemble import build_simulation
    from sphfoam.case.case import Case
    from sphfoam.case.edit import clone_case
    from sphfoam.engine.state import ParticleState
    from sphfoam.io.fields import read_state
    from sphfoam.setup import setup_case

    with tempfile.TemporaryDirectory() as tmp:
        edits = {"system/controlDict:functions": {}, **edits}
        if dx:
            edits["system/particleDict:dx"] = dx
        d = clone_case(case_src, Path(tmp) / case_src.name, edits)
        case = Case(d)
        setup_case(case, log=lambda *_: None)
        sim = build_simulation(case, ParticleState.from_fields(read_state(d / "0")),
                               backend="cuda")
        for _ in range(2):
            sim.step()
        if getattr(sim.module, "HAS_FILTER", False):
            sim.filter_density()
        sim.health_scan(0.0, 1e30, 1e30)          # the time loop's checks
        sim.keep_snapshot(None)
    out.write_bytes(pickle.dumps(list(launches)))


def _pretend_device(cc) -> None:
    """Device functions are compiled for the current device's compute capability
    (numba-cuda's dispatcher asks the driver); with no driver, answer ``cc``."""
    from types import SimpleNamespace

    import numba.cuda.dispatcher as disp

    disp.get_current_device = lambda: SimpleNamespace(compute_capability=cc)


def _module(name: str, path: str):
    if name in sys.modules:
        return sys.modules[name]
    try:
        return importlib.import_module(name)
    except ImportError:
        spec = importlib.util.spec_from_file_location(name, path)
        mod = importlib.util.module_from_spec(spec)
        sys.modules[name] = mod
        spec.loader.exec_module(mod)
        return mod


def compile_launches(launches, cc=(9, 0)) -> list[tuple[str, str]]:
    """(kernel, "ok" or the error) for every recorded launch."""
    from numba import cuda

    _pretend_device(cc)
    out = []
    for modname, path, name, sig, made_by in launches:
        label = f"{modname.rsplit('.', 1)[-1][:28]}.{name}"
        try:
            if made_by:
                fmod, factory, amod, arg = made_by
                kernel = getattr(importlib.import_module(fmod), factory)(
                    getattr(importlib.import_module(amod), arg))
                label += f"({arg})"
            else:
                kernel = getattr(_module(modname, path), name)
            ptx, _ = cuda.compile_ptx(kernel.py_func, sig, cc=cc)
            ok = f".target sm_{cc[0]}{cc[1]}" in ptx
            out.append((label, "ok" if ok else "no target line in the PTX"))
        except Exception as e:  # noqa: BLE001  (reported; the caller fails)
            out.append((label, f"{type(e).__name__}: {str(e)[:1500]}"))
    return out


def check_case(src: Path, dx: float | None, cc, edits: str = "{}") -> list[tuple[str, str]]:
    with tempfile.TemporaryDirectory() as tmp:
        rec = Path(tmp) / "launches.pkl"
        env = dict(os.environ, NUMBA_ENABLE_CUDASIM="1",
                   PYTHONPATH=os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")]))
        cmd = [sys.executable, "-m", "sphfoam.cudaptx", "--record", str(src),
               "--to", str(rec), "--edits", edits] + (["--dx", str(dx)] if dx else [])
        p = subprocess.run(cmd, env=env, capture_output=True, text=True)
        if p.returncode or not rec.exists():
            return [("(recording under the simulator)",
                     (p.stdout[-1000:] + p.stderr[-2000:]).strip() or "failed")]
        return compile_launches(pickle.loads(rec.read_bytes()), cc)


#: where each family is chosen (``constant/sphProperties`` unless named)
_FAMILY_FILE = {"integrator": "system/sphSchemes"}
#: models that need a partner in another family
_PARTNERS = {("continuity", "riemann"): {"momentum": "riemann"},
             ("momentum", "riemann"): {"continuity": "riemann"}}
#: families of the pipeline (the others, e.g. wave makers, are not kernels' code)
_FAMILIES = ("kernel", "continuity", "momentum", "viscosity", "turbulence", "boundary",
             "densityFilter", "velocityCorrection", "kernelCorrection", "particleShifting",
             "integrator")


def every_model_edits() -> list[tuple[str, dict]]:
    """(label, edits of the dam break) selecting each registered pipeline model once."""
    from sphfoam import registry

    out = []
    for family in _FAMILIES:
        for name in sorted(registry.families().get(family, {})):
            if name == "none":
                continue
            edits = {}
            for fam, other in {family: name, **_PARTNERS.get((family, name), {})}.items():
                f = _FAMILY_FILE.get(fam, "constant/sphProperties")
                edits[f"{f}:{fam}"] = {"type": other}
            out.append((f"{family} {name}", edits))
    out.append(("precision single", {"system/sphSchemes:precision": "single"}))
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("cases", nargs="*")
    ap.add_argument("--every-model", action="store_true")
    ap.add_argument("--dx", type=float, default=None)
    ap.add_argument("--cc", default="9.0")
    ap.add_argument("--edits", default="{}", help="edits of the case as JSON "
                    "({\"file:key.sub\": value}), applied to every case")
    ap.add_argument("--record", action="store_true", help=argparse.SUPPRESS)
    ap.add_argument("--to", default=None, help=argparse.SUPPRESS)
    a = ap.parse_args(argv)
    srcs = []
    for c in a.cases:
        p = Path(c)
        if not p.exists():
            p = next((q / c for q in (ROOT / "tutorials", ROOT / "benchmarks" / "cases")
                      if (q / c).exists()), p)
        srcs.append(p)
    if a.record:
        _record(srcs[0], a.dx, Path(a.to), json.loads(a.edits))
        return 0
    cc = tuple(int(x) for x in a.cc.split("."))
    failed = 0
    if a.every_model:
        src = ROOT / "tutorials" / "damBreak"
        for label, edits in every_model_edits():
            res = check_case(src, a.dx or 0.1, cc, json.dumps(edits))
            bad = [f"{k}: {v}" for k, v in res if v != "ok"]
            print(f"{label}: {len(res) - len(bad)} kernels ok" +
                  (f"; FAILED {'; '.join(bad)}" if bad else ""), flush=True)
            failed += bool(bad)
    for src in srcs:
        for label, status in check_case(src, a.dx, cc, a.edits):
            print(f"{src.name}: {label}: {status}", flush=True)
            failed += status != "ok"
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
