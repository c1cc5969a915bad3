"""Built-in models; importing this package registers them all."""

from sphfoam.models import (  # noqa: F401
    boundaries,
    eos,
    equations,
    integrators,
    kernels,
    viscosity,
)
