"""The CUDA backend's kernels compile to PTX for sm_90 (the H100/H200) with no GPU
(:mod:`sphfoam.cudaptx`): the matched dam break's every launched kernel here; every
tutorial's with ``python -m sphfoam.cudaptx TUTORIAL ...`` (the separate check,
docs/developing.md). Needs NVIDIA's NVVM, which numba-cuda's CUDA 13 wheels bring; skipped
where it is missing."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

pytest.importorskip("numba.cuda")

ROOT = Path(__file__).resolve().parents[1]


def _nvvm() -> bool:
    try:
        from numba.cuda.cudadrv.nvvm import NVVM

        NVVM()
    except Exception:  # noqa: BLE001  (no NVVM library: nothing to compile with)
        return False
    return True


@pytest.mark.skipif(not _nvvm(), reason="no NVVM (pip install 'numba-cuda[cu13]')")
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
