"""The CUDA backend's kernels compile to PTX for sm_90 (the H100/H200) with no GPU
(:mod:`sphfoam.cudaptx`): the matched dam break's every launched kernel here; every
tutorial's with ``python -m sphfoam.cudaptx TUTORIAL ...`` (the separate check,
docs/developing.md). Needs NVIDIA's NVVM and NVRTC (``pip install "numba-cuda[cu13]"``);
skipped, saying why, where they are missing."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

pytest.importorskip("numba.cuda")

ROOT = Path(__file__).resolve().parents[1]


_PROBE = """
from numba import cuda, types
from sphfoam.cudaptx import _pretend_device
_pretend_device((9, 0))
twice = cuda.jit(device=True)(lambda v: 2.0 * v)
def k(a):
    i = cuda.grid(1)
    if i < a.shape[0]:
        a[i] = twice(a[i])
cuda.compile_ptx(k, (types.float64[::1],), cc=(9, 0))
"""


def _toolchain() -> str:
    """'' where NVVM and NVRTC compile a kernel calling a device function for sm_90 (in a
    subprocess, as the check does), else why not."""
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    env.pop("NUMBA_ENABLE_CUDASIM", None)
    p = subprocess.run([sys.executable, "-c", _PROBE], env=env, capture_output=True,
                       text=True, timeout=300)
    return "" if p.returncode == 0 else (p.stderr.strip().splitlines() or ["failed"])[-1]


_WHY_NOT = _toolchain()


@pytest.mark.skipif(bool(_WHY_NOT), reason="no NVVM/NVRTC to compile with (pip install "
                    f"'numba-cuda[cu13]'): {_WHY_NOT[:200]}")
def test_every_launched_kernel_compiles_to_sm90_ptx():
    env = dict(os.environ, PYTHONPATH=str(ROOT), NUMBA_NUM_THREADS="1")
    env.pop("NUMBA_ENABLE_CUDASIM", None)
    p = subprocess.run([sys.executable, "-m", "sphfoam.cudaptx", "damBreakMatched",
                        "--dx", "0.1", "--cc", "9.0"], env=env, capture_output=True,
                       text=True, timeout=900)
    lines = p.stdout.splitlines()
    kernels = {ln.split(": ")[1] for ln in lines}
    # the cell list, the neighbour list, the stages, the reductions and the update
    for k in ("device.bin_particles", "device.time_step_reduce", "rates",
              "fill_neighbours", "update_step"):
        assert any(k in name for name in kernels), (k, p.stdout, p.stderr[-2000:])
    failed = [ln for ln in lines if not ln.endswith(": ok")]
    assert p.returncode == 0 and not failed, "\n".join(failed) + p.stderr[-3000:]


@pytest.mark.skipif(bool(_WHY_NOT), reason="no NVVM/NVRTC to compile with (pip install "
                    f"'numba-cuda[cu13]'): {_WHY_NOT[:200]}")
def test_mdbc_kernels_compile_with_and_without_slip():
    """mDBC's fit kernel holds the free-slip branch whatever the case selects: a device
    types it with the no-slip case's arguments too (the simulator does not)."""
    env = dict(os.environ, PYTHONPATH=str(ROOT), NUMBA_NUM_THREADS="1")
    env.pop("NUMBA_ENABLE_CUDASIM", None)
    for slip in ("yes", "no"):
        edits = '{"constant/sphProperties:boundary": {"type": "mDBC", "noSlip": "%s"}}' % slip
        p = subprocess.run([sys.executable, "-m", "sphfoam.cudaptx", "damBreakMatched",
                            "--dx", "0.2", "--edits", edits], env=env, capture_output=True,
                           text=True, timeout=900)
        lines = p.stdout.splitlines()
        assert any("fit_walls" in ln for ln in lines), p.stdout + p.stderr[-2000:]
        failed = [ln for ln in lines if not ln.endswith(": ok")]
        assert p.returncode == 0 and not failed, "\n".join(failed) + p.stderr[-3000:]
