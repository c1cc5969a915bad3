"""The worked example of docs/developing.md: a kernel, a viscosity and a function object
defined here, outside ``sphfoam/``, registered, selected by a case and run.

Nothing in ``sphfoam/`` knows these models: they reach the engine through the contract alone
(terms, params, imports; the function-object interface).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from numba import njit
from pydantic import Field
from scipy.integrate import trapezoid

from sphfoam import registry
from sphfoam.engine.terms import Term
from sphfoam.models.kernels import Kernel
from sphfoam.models.viscosity import VISCOUS_SEES, Viscosity
from sphfoam.registry import Coeffs, register
from sphfoam.sampling.base import FunctionObject, FunctionObjectCoeffs
from sphfoam.engine.state import FLUID


# --- a kernel: Wendland C4 (Wendland 1995; Dehnen & Aly 2012, Table 1), in 2-D and 3-D ------
@njit(cache=True, fastmath=True, inline="always")
def wendland_c4_f(q):
    """f(q) = (1 - q/2)^6 (35 q^2 / 12 + 3 q + 1) for q < 2."""
    t = max(1.0 - 0.5 * q, 0.0)
    return t**6 * (35.0 / 12.0 * q * q + 3.0 * q + 1.0)


@njit(cache=True, fastmath=True, inline="always")
def wendland_c4_dfdq_q(q):
    """(df/dq) / q = -(14/3) (1 - q/2)^5 (1 + 5 q / 2)."""
    t = max(1.0 - 0.5 * q, 0.0)
    return -14.0 / 3.0 * t**5 * (1.0 + 2.5 * q)


class WendlandC4(Kernel):
    name = "wendlandC4Example"
    doc = ("Wendland C4, alpha = 9/(4 pi) in 2-D, 495/(256 pi) in 3-D, support 2h (the "
           "developer guide's example)")
    support = 2.0
    alpha_2d = 9.0 / (4.0 * math.pi)
    alpha_3d = 495.0 / (256.0 * math.pi)
    f_name, dfdq_q_name = "wendland_c4_f", "wendland_c4_dfdq_q"

    def imports(self):
        # the generated module imports the two functions from where they are defined
        return [f"from {__name__} import {self.f_name} as kernel_f, "
                f"{self.dfdq_q_name} as kernel_dfdq_q"]

    @property
    def f_jit(self):
        return wendland_c4_f

    @property
    def dfdq_q_jit(self):
        return wendland_c4_dfdq_q


# --- a viscosity: artificial viscosity with the reference sound speed c0 ---------------------
class ArtificialC0(Viscosity):
    """Pi_ab = -alpha h c0 / rhobar_ab v_ab.r_ab / (r_ab^2 + eta^2) for approaching pairs:
    T(3.32) with c0 in place of (c_a + c_b)/2."""

    name = "artificialC0Example"
    doc = "artificial viscosity of T(3.32) with the reference sound speed c0"

    class Coeffs(Coeffs):
        alpha: float = Field(0.1, ge=0.0)

    def params(self, ctx):
        return {"visc_ac0": self.coeffs.alpha * ctx.c0}

    def terms(self):
        return [Term("viscosity", ("rates",), sees=VISCOUS_SEES, reads=("gradW",),
                     writes=("acc",), pair=(
                         "if vdotr < 0.0:\n"
                         "    pi_c0 = -visc_ac0 * h * 2.0 / (rhoa + rhob) * vdotr / (r2 + eta2)\n"
                         "    acc_@ -= mb * pi_c0 * gW@"))]


# --- a 3-D-ready viscosity: written once with @ and dot(...), for 2 and 3 components ---------
class LaminarExample(Viscosity):
    """Laminar viscosity of Lo & Shao (2002):
    dv_a/dt = sum_b 4 nu m_b / (rho_a + rho_b) r_ab . grad_a W_ab / (r_ab^2 + eta^2) v_ab."""

    name = "laminarExample"
    doc = "laminar viscosity of Lo & Shao (2002), written once for 2-D and 3-D"

    def params(self, ctx):
        return {"visc_ex4nu": 4.0 * ctx.nu}

    def terms(self):
        return [Term("viscosity", ("rates",), sees=VISCOUS_SEES, reads=("gradW",),
                     writes=("acc",), pair=(
                         "lam_ex = visc_ex4nu * mb / (rhoa + rhob) * dot(d@_ab, gW@) / (r2 + eta2)\n"
                         "acc_@ += lam_ex * U@_ab"))]


# --- a function object: the kinetic energy of the fluid ---------------------------------------
class KineticEnergy(FunctionObject):
    name = "kineticEnergyExample"
    doc = "kinetic energy of the fluid per unit width (J/m)"
    columns = ("time", "KE")

    class Coeffs(FunctionObjectCoeffs):
        pass

    def execute(self, sim):
        st = sim.state
        f = st.kind == FLUID
        self.write_row([sim.time, 0.5 * float(np.sum(st.m[f] * (st.u[f]**2 + st.v[f]**2)))])


@pytest.fixture(autouse=True)
def example_models():
    """Register the three models for this module's tests only (registered at import, they
    would join the registry-wide parametrisations of other test modules)."""
    for cls in (WendlandC4, ArtificialC0, LaminarExample, KineticEnergy):
        register(cls)
    yield
    for cls in (WendlandC4, ArtificialC0, LaminarExample, KineticEnergy):
        registry.unregister(cls)


def test_example_kernel_is_normalised_and_its_gradient_consistent():
    k = registry.build("kernel", {"type": "wendlandC4Example"})
    h = 1.0
    r = np.linspace(0.0, 2.0, 20001)
    w = k.W(r, h)
    integral = trapezoid(2.0 * np.pi * r * w, r)
    assert abs(integral - 1.0) < 1e-6
    assert abs(trapezoid(4.0 * np.pi * r * r * k.W(r, h, dim=3), r) - 1.0) < 1e-6
    q = np.linspace(0.05, 1.95, 39)
    eps = 1e-6
    fd = (np.vectorize(wendland_c4_f)(q + eps) - np.vectorize(wendland_c4_f)(q - eps)) / (2 * eps)
    np.testing.assert_allclose(np.vectorize(wendland_c4_dfdq_q)(q) * q, fd, rtol=1e-6,
                               atol=1e-9)


def test_example_models_selected_by_a_case_and_run(tutorial):
    from sphfoam.timeloop import run_case

    case = tutorial("hydrostaticTank", {
        "constant/sphProperties:kernel": {"type": "wendlandC4Example", "hdx": 1.3},
        "constant/sphProperties:viscosity": {"type": "artificialC0Example", "alpha": 0.1},
        "system/particleDict:dx": 0.04,
        "system/controlDict:endTime": 0.05, "system/controlDict:writeInterval": 0.05,
        "system/controlDict:functions": {"ke": {"type": "kineticEnergyExample"}}})
    report = run_case(case, progress=False, echo=None)
    assert report.steps > 10 and report.failure is None
    log = (case / "log.sphfoam").read_text()
    assert "kernel=wendlandC4Example" in log and "viscosity=artificialC0Example" in log
    ke = np.loadtxt(case / "postProcessing" / "ke" / "0" / "ke.dat", ndmin=2)
    assert ke.shape[0] == report.steps + 1 and np.all(np.isfinite(ke[:, 1]))
    # a tank at rest: the fluid's kinetic energy stays small against its potential energy
    assert ke[:, 1].max() < 1e-2 * 1000 * 9.81 * 0.4**2 / 2 * 0.5


def test_example_3d_ready_term_expands_per_dimension():
    """The example viscosity's one line of pair code is a dot product of two and of three
    components; the plan accepts it in 3-D."""
    from sphfoam.engine.bodies import expand

    (t,) = registry.build("viscosity", {"type": "laminarExample"}).terms()
    assert t.dims == (2, 3)
    assert expand(t.pair, 2).splitlines() == [
        "lam_ex = visc_ex4nu * mb / (rhoa + rhob) * (dx_ab * gWx + dy_ab * gWy) / (r2 + eta2)",
        "acc_x += lam_ex * u_ab", "acc_y += lam_ex * v_ab"]
    three = expand(t.pair, 3).splitlines()
    assert "dz_ab * gWz" in three[0] and three[-1] == "acc_z += lam_ex * w_ab"


def test_example_3d_ready_viscosity_run_in_2d(tutorial):
    from sphfoam.timeloop import run_case

    case = tutorial("hydrostaticTank", {
        "constant/sphProperties:viscosity": {"type": "laminarExample"},
        "system/particleDict:dx": 0.04,
        "system/controlDict:endTime": 0.05, "system/controlDict:writeInterval": 0.05})
    report = run_case(case, progress=False, echo=None)
    assert report.steps > 10 and report.failure is None
    assert "viscosity=laminarExample" in (case / "log.sphfoam").read_text()
