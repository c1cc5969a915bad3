"""The CUDA backend (numba-cuda): the same plan and loop bodies as the CPU backend, one
device thread per particle, every array on the device between writes.

* :mod:`~sphfoam.engine.cuda.emit`: the generated module of ``cuda.jit`` kernels (one per
  stage, gather over full neighbour lists; the cell list, the list and the reductions);
* :mod:`~sphfoam.engine.cuda.build`: the refusals by name, the module cached on disk;
* :mod:`~sphfoam.engine.cuda.runtime`: :class:`CudaSimulation`, the ``Simulation``'s
  interface to the time loop over device arrays.
* :mod:`~sphfoam.engine.cuda.forms`, :mod:`~sphfoam.engine.cuda.context`: the device forms
  of the models' run-time hooks (a model names its own, ``device_form``) and what they see
  of the simulation.

Nothing here imports the CPU emitter or pipeline.
"""

from __future__ import annotations


class BackendUnavailable(RuntimeError):
    """numba-cuda is not installed, or there is no CUDA device (and no simulator)."""


def cuda_module():
    """``numba.cuda`` when it can run kernels (a device, or ``NUMBA_ENABLE_CUDASIM=1``);
    else :class:`BackendUnavailable` with what to do."""
    import numpy as np

    if not hasattr(np, "row_stack"):
        # numpy 2.5 removed the alias; numba-cuda releases before the fix still register an
        # overload for it when numba.cuda is imported (seen on an H200 machine)
        np.row_stack = np.vstack
    try:
        from numba import cuda
    except ImportError as e:  # pragma: no cover - depends on the installation
        raise BackendUnavailable("backend cuda needs numba-cuda: pip install 'sphfoam[gpu]' "
                                 f"(numba.cuda could not be imported: {e})") from None
    try:
        ok = cuda.is_available()
    except Exception as e:  # noqa: BLE001  (the driver's own error, reported in words)
        raise BackendUnavailable(f"backend cuda: no usable CUDA driver ({e})") from None
    from numba import config

    # small cases launch few blocks by design; the warning would print at every launch
    config.CUDA_LOW_OCCUPANCY_WARNINGS = 0
    if not ok:
        raise BackendUnavailable("backend cuda: no CUDA device found (set "
                                 "NUMBA_ENABLE_CUDASIM=1 to run on numba's simulator)")
    return cuda
