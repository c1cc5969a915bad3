"""Density filters (T §3.7): periodic re-initialisation passes and delta-SPH diffusion.

The continuity equation lets the density of neighbouring particles drift apart (a noisy
pressure field) and away from the mass/volume the particles occupy. Three remedies:

* ``shepard``: every N steps, the Shepard filter of Dalrymple & Rogers (2006), T(3.69);
* ``mlsReinitialisation``: every N steps, the first-order moving-least-squares
  re-initialisation of Colagrossi & Landrini (2003), T(3.64)-(3.68);
* ``deltaSPH``: no periodic pass but a diffusive term in the continuity equation at every
  evaluation of the rates, Molteni & Colagrossi (2009).

The two periodic passes sum over every neighbour b of a fluid particle a, fluid and wall
alike, and include a itself (the generated neighbour loop skips b = a, so the self term
m_a W(0) is added before the loop). Wall particles keep their density.
"""

from __future__ import annotations

from pydantic import Field

from sphfoam.engine.schedule import Schedule
from sphfoam.engine.terms import Term
from sphfoam.models.base import CaseContext, PipelineModel
from sphfoam.registry import Coeffs, register


class DensityFilter(PipelineModel):
    family = "densityFilter"
    prefix = "filt_"
    #: the periodic pass over every neighbour of a fluid particle a, setting ``rho_new``;
    #: empty: no pass, no ``density_filter``
    filter_init: str = ""
    filter_pair: str = ""
    filter_final: str = ""
    #: the dimensions the pass has code for
    filter_dims: tuple[int, ...] = (2, 3)

    def terms(self):
        if not self.filter_pair:
            return []
        return [Term("densityFilter", ("filter",), init=self.filter_init,
                     pair=self.filter_pair, final=self.filter_final, sees=("all",),
                     reads=("W",), writes=("rho_new",), dims=self.filter_dims)]

    def schedule(self):
        """The periodic pass runs before the steps whose index is a multiple of ``every``."""
        every = getattr(self.coeffs, "every", None)
        return Schedule.every(every) if self.filter_pair and every else None


#: the self contribution b = a of the kernel sums: W(0) = kern_w f(0) (the kernel's names)
_SELF = "filt_w0 = kern_w * kernel_f(0.0)\n"


@register
class Shepard(DensityFilter):
    """Shepard filter: the density becomes the kernel-weighted, volume-weighted average of
    the densities around the particle (itself included),
    rho_a = sum_b m_b W_ab / sum_b (m_b / rho_b) W_ab, T(3.69). Zeroth-order consistent: a
    uniform field is kept everywhere, a linear one only where the support is full and the
    particle volumes are uniform. The thesis quotes Dalrymple & Rogers (2006) applying it
    once every forty steps, the default of ``every``.
    """

    name = "shepard"
    doc = ("Shepard filter, Dalrymple & Rogers (2006), T(3.69): every N steps "
           "rho_a = sum_b m_b W_ab / sum_b (m_b/rho_b) W_ab")

    class Coeffs(Coeffs):
        every: int = Field(40, ge=1, description="apply the filter once every this many time "
                           "steps (forty in T §3.7, after Dalrymple & Rogers 2006)")

    filter_init = _SELF + (
        "filt_num = m[a] * filt_w0\n"
        "filt_den = m[a] / rhoa * filt_w0\n")
    filter_pair = (
        "filt_num += mb * Wab\n"
        "filt_den += mb / rhob * Wab\n")
    filter_final = "rho_new = filt_num / filt_den\n"


@register
class MLSReinitialisation(DensityFilter):
    """First-order moving-least-squares re-initialisation of Colagrossi & Landrini (2003),
    T(3.64)-(3.68): rho_a = sum_b m_b W^MLS_ab with W^MLS_ab = (beta0 + beta1 x_ab + beta2 y_ab)
    W_ab, x_ab = x_a - x_b, (beta0, beta1, beta2) = A^-1 (1, 0, 0) and
    A = sum_b W_ab V_b [[1, x_ab, y_ab], [x_ab, x_ab^2, x_ab y_ab], [y_ab, x_ab y_ab, y_ab^2]],
    V_b = m_b / rho_b. A linear density field is reproduced exactly wherever A is invertible,
    at a free surface or a wall too.

    In 3-D the basis is (1, x_ab, y_ab, z_ab) and A 4 x 4, the same T(3.64)-(3.68) in d = 3
    (the guard det A / (A00 A11 A22 A33)). Moments are taken in units of h (x_ab / h), the
    3 x 3 (4 x 4) system is solved in closed form
    (only the first column of A^-1 is needed: the cofactors of A's first row over det A) and
    the sums m_b W_ab (1, x_ab, y_ab) are accumulated in the same neighbour loop, so one pass
    suffices. Guard: det A / (A00 A11 A22) lies in [0, 1] (Hadamard's inequality; 1 for a
    symmetric neighbourhood, 0 when the neighbours are collinear or absent); where it is below
    ``minDetRatio`` (an isolated or nearly isolated particle, e.g. in a splash), or where the
    corrected sum would not be positive, that particle falls back to the Shepard filter
    T(3.69) of the same sums. The thesis gives "once every twenty to fifty time steps";
    ``every`` defaults to 30.
    """

    name = "mlsReinitialisation"
    doc = ("MLS density re-initialisation, Colagrossi & Landrini (2003), T(3.64)-(3.68): every "
           "N steps rho_a = sum_b m_b W^MLS_ab, first-order consistent (Shepard fallback)")

    class Coeffs(Coeffs):
        every: int = Field(30, ge=1, description="apply the re-initialisation once every this "
                           "many time steps (T §3.7: every twenty to fifty)")
        minDetRatio: float = Field(
            1e-3, ge=0.0, lt=1.0, description="particles whose moment matrix has "
            "det A / (A00 A11 A22) below this (ill-conditioned: too few or collinear "
            "neighbours) get the Shepard filter T(3.69) instead")

    def params(self, ctx: CaseContext):
        return {"filt_min_det": self.coeffs.minDetRatio}

    filter_init = _SELF + (
        "filt_va = m[a] / rhoa * filt_w0\n"
        "filt_a00 = filt_va\n"          # the self term: x_aa = y_aa = 0
        "filt_a01 = 0.0\n"
        "filt_a02 = 0.0\n"
        "filt_a11 = 0.0\n"
        "filt_a12 = 0.0\n"
        "filt_a22 = 0.0\n"
        "filt_m0 = m[a] * filt_w0\n"
        "filt_m1 = 0.0\n"
        "filt_m2 = 0.0\n")
    filter_pair = (
        "filt_xs = dx_ab * inv_h\n"
        "filt_ys = dy_ab * inv_h\n"
        "filt_wv = Wab * mb / rhob\n"
        "filt_a00 += filt_wv\n"
        "filt_a01 += filt_wv * filt_xs\n"
        "filt_a02 += filt_wv * filt_ys\n"
        "filt_a11 += filt_wv * filt_xs * filt_xs\n"
        "filt_a12 += filt_wv * filt_xs * filt_ys\n"
        "filt_a22 += filt_wv * filt_ys * filt_ys\n"
        "filt_mw = mb * Wab\n"
        "filt_m0 += filt_mw\n"
        "filt_m1 += filt_mw * filt_xs\n"
        "filt_m2 += filt_mw * filt_ys\n")
    filter_final = (
        "# first column of A^-1 = cofactors of the first row / det A (A is symmetric)\n"
        "filt_cof0 = filt_a11 * filt_a22 - filt_a12 * filt_a12\n"
        "filt_cof1 = filt_a02 * filt_a12 - filt_a01 * filt_a22\n"
        "filt_cof2 = filt_a01 * filt_a12 - filt_a02 * filt_a11\n"
        "filt_det = filt_a00 * filt_cof0 + filt_a01 * filt_cof1 + filt_a02 * filt_cof2\n"
        "rho_new = filt_m0 / filt_a00\n"                     # Shepard, T(3.69)
        "if filt_det > filt_min_det * filt_a00 * filt_a11 * filt_a22:\n"
        "    filt_mls = (filt_cof0 * filt_m0 + filt_cof1 * filt_m1\n"
        "                + filt_cof2 * filt_m2) / filt_det\n"
        "    if filt_mls > 0.0:\n"
        "        rho_new = filt_mls\n")

    def terms(self):
        """The 2-D pass above and its 3-D form (the basis (1, x, y, z), A 4 x 4)."""
        return [Term("densityFilter", ("filter",),
                     init={2: self.filter_init, 3: _mls_3d("init")},
                     pair={2: self.filter_pair, 3: _mls_3d("pair")},
                     final={2: self.filter_final, 3: _mls_3d("final")}, sees=("all",),
                     reads=("W",), writes=("rho_new",))]


def _det3(e, rows, cols) -> str:
    """The determinant of the 3 x 3 submatrix (rows, cols) of the matrix whose entry
    (i, j) is the expression ``e(i, j)``, by the rule of Sarrus."""
    (r0, r1, r2), (c0, c1, c2) = rows, cols
    return (f"{e(r0, c0)} * ({e(r1, c1)} * {e(r2, c2)} - {e(r1, c2)} * {e(r2, c1)})"
            f" - {e(r0, c1)} * ({e(r1, c0)} * {e(r2, c2)} - {e(r1, c2)} * {e(r2, c0)})"
            f" + {e(r0, c2)} * ({e(r1, c0)} * {e(r2, c1)} - {e(r1, c1)} * {e(r2, c0)})")


def _sym(prefix: str):
    """The entry (i, j) of a symmetric matrix stored as its upper triangle ``prefix{i}{j}``."""
    return lambda i, j: f"{prefix}{min(i, j)}{max(i, j)}"


def _mls_3d(part: str) -> str:
    """T(3.64)-(3.68) in three dimensions: the basis (1, x, y, z)/h, A 4 x 4 (its upper
    triangle ``filt_a{i}{j}``); beta = A^-1 e_0 is the first column of A^-1, the cofactors of
    A's first row over det A; the same Hadamard guard det A / (A00 A11 A22 A33) and Shepard
    fallback as in 2-D."""
    if part == "init":
        return _SELF + "filt_va = m[a] / rhoa * filt_w0\nfilt_a00 = filt_va\n" + "".join(
            f"filt_a{i}{j} = 0.0\n" for i in range(4) for j in range(i, 4) if (i, j) != (0, 0)) \
            + "filt_m0 = m[a] * filt_w0\nfilt_m1 = 0.0\nfilt_m2 = 0.0\nfilt_m3 = 0.0\n"
    if part == "pair":
        p = ("filt_p1 = dx_ab * inv_h\nfilt_p2 = dy_ab * inv_h\nfilt_p3 = dz_ab * inv_h\n"
             "filt_wv = Wab * mb / rhob\nfilt_a00 += filt_wv\n")
        p += "".join(f"filt_a0{j} += filt_wv * filt_p{j}\n" for j in range(1, 4))
        p += "".join(f"filt_a{i}{j} += filt_wv * filt_p{i} * filt_p{j}\n"
                     for i in range(1, 4) for j in range(i, 4))
        p += "filt_mw = mb * Wab\nfilt_m0 += filt_mw\n"
        return p + "".join(f"filt_m{j} += filt_mw * filt_p{j}\n" for j in range(1, 4))
    a = _sym("filt_a")
    out = ["# first column of A^-1 = cofactors of the first row / det A (A is symmetric)"]
    for j in range(4):
        cols = [c for c in range(4) if c != j]
        sign = "" if j % 2 == 0 else "-"
        out.append(f"filt_cof{j} = {sign}({_det3(a, (1, 2, 3), cols)})")
    out += ["filt_det = filt_a00 * filt_cof0 + filt_a01 * filt_cof1 + filt_a02 * filt_cof2"
            " + filt_a03 * filt_cof3",
            "rho_new = filt_m0 / filt_a00",
            "if filt_det > filt_min_det * filt_a00 * filt_a11 * filt_a22 * filt_a33:",
            "    filt_mls = (filt_cof0 * filt_m0 + filt_cof1 * filt_m1 + filt_cof2 * filt_m2",
            "                + filt_cof3 * filt_m3) / filt_det",
            "    if filt_mls > 0.0:",
            "        rho_new = filt_mls"]
    return "\n".join(out) + "\n"


#: the ``walls`` option of the delta-SPH filters that diffuse the density over the walls
WALLS_DOC = (
    "yes (the default): wall particles (stationary ghosts, Adami's walls) are neighbours of "
    "the diffusion with their own density, which the term does not change, so each "
    "fluid-wall pair moves density into or out of the fluid; no: fluid neighbours (and "
    "mirrored ghosts) only, so the pair terms cancel over the fluid and its sum of V rho is "
    "unchanged by them (at a wall the support is then truncated, as at the free surface)")


def diffusion_sees(walls: bool) -> dict:
    """The neighbours a delta-SPH pair term sees: the default's (fluid, ghosts, wet walls),
    or with ``walls no`` the fluid and mirrored ghosts only."""
    return {} if walls else {"sees": ("fluid", "ghost")}


@register
class DeltaSPH(DensityFilter):
    """delta-SPH density diffusion of Molteni & Colagrossi (2009), added to drho_a/dt at every
    evaluation of the rates (no periodic pass, no ``every``):
    drho_a/dt += delta h c0 sum_b psi_ab . grad_a W_ab V_b with
    psi_ab = 2 (rho_a - rho_b) r_ab / (|r_ab|^2 + eta^2), r_ab = r_a - r_b, V_b = m_b / rho_b.
    (Written with r_ba = r_b - r_a, as in the paper, psi = 2 (rho_b - rho_a) r_ba / |r_ba|^2.)
    Since r_ab . grad_a W_ab < 0, a particle denser than its neighbours loses density; the
    pair term is antisymmetric, so sum_a V_a drho_a is unchanged by it. eta^2 = (0.1 h)^2 is
    the guard of T(3.32). Wall neighbours take part with their own density; wall particles'
    rates get no diffusion (``walls no``: fluid neighbours and mirrored ghosts only, see
    :data:`WALLS_DOC`).
    """

    name = "deltaSPH"
    doc = ("delta-SPH density diffusion, Molteni & Colagrossi (2009): drho_a/dt += delta h c0 "
           "sum_b psi_ab.grad_a W_ab V_b, psi_ab = 2(rho_a - rho_b) r_ab/(r_ab^2 + eta^2)")

    class Coeffs(Coeffs):
        delta: float = Field(0.1, ge=0.0, description="dimensionless diffusion coefficient "
                             "delta (0.1 in Molteni & Colagrossi 2009)")
        walls: bool = Field(True, description=WALLS_DOC)

    def params(self, ctx: CaseContext):
        if not ctx.c0 > 0.0:
            raise ValueError("deltaSPH needs the reference speed of sound c0 > 0 "
                             "(CaseContext.c0)")
        return {"filt_dc0": self.coeffs.delta * ctx.c0}

    def terms(self):
        return [Term("densityDiffusion", ("rates", "density"), reads=("gradW",),
                     writes=("drho",), **diffusion_sees(self.coeffs.walls), pair=(
                         "filt_psi = 2.0 * (rhoa - rhob) * dot(d@_ab, gW@) / "
                         "(r2 + eta2)\n"
                         "drho_a += filt_dc0 * h * filt_psi * mb / rhob\n"))]
