"""Built-in models; importing this package registers them all."""

import sphfoam.sampling.damBreak  # noqa: F401  (function objects)

from sphfoam.models import (  # noqa: F401
    boundaries,
    eos,
    equations,
    integrators,
    kernels,
    noop,
    viscosity,
)
