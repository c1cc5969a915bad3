"""Built-in models: what a case selects (``constant/sphProperties``, particleDict walls,
waveProperties), registered by the modules of ``sphfoam.registry.MODEL_MODULES``.

One module per family:

=================== =====================================================================
family              module(s)
=================== =====================================================================
kernel              ``kernels``
equationOfState     ``eos``
continuity          ``equations``; ``riemann`` (Riemann-solver forms)
momentum            ``equations``; ``riemann`` (Riemann-solver forms)
viscosity           ``viscosity``
turbulence          ``turbulence`` (with ``walllaw``, its wall condition)
boundary            ``boundaries`` (with ``mirror``, mirrored ghosts); ``adami`` (Adami's walls);
                    ``mdbc`` (the modified dynamic boundary)
densityFilter       ``filters``; ``diffusion`` (delta-SPH density diffusion)
velocityCorrection  ``corrections``
kernelCorrection    ``corrections``
particleShifting    ``shifting``
integrator          ``integrators``
motion              ``motion``
waveMaker           ``wavemakers``; ``goring`` (Goring's paddle, ``goring`` and ``massFlux``)
waveTheory          ``wavetheory`` (the solutions are in :mod:`sphfoam.reference.solitary`)
=================== =====================================================================

``noop`` holds the ``none`` entry of the optional families (turbulence, densityFilter,
velocityCorrection, kernelCorrection, particleShifting) and ``base`` the contract a pipeline
model implements. Elsewhere: function objects (``functionObject``) in :mod:`sphfoam.sampling`,
study metrics (``metric``) in :mod:`sphfoam.study`, reference solutions in
:mod:`sphfoam.reference`.
"""
