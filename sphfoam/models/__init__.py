"""Built-in models; importing this package registers them all."""

import sphfoam.sampling.damBreak  # noqa: F401  (function objects)
import sphfoam.sampling.profiles  # noqa: F401
import sphfoam.sampling.waves  # noqa: F401

from sphfoam.models import (  # noqa: F401
    boundaries,
    corrections,
    eos,
    equations,
    filters,
    goring,
    integrators,
    kernels,
    metrics,
    motion,
    noop,
    turbulence,
    viscosity,
    wavemakers,
    wavetheory,
)
