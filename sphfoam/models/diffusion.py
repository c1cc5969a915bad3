"""Low-dissipation density diffusion (issue 13): two refinements of the delta-SPH term of
Molteni & Colagrossi (2009) (``deltaSPH`` in ``sphfoam.models.filters``), selected in the
``densityFilter`` family:

* ``antuonoDeltaSPH``: the renormalised form of Antuono, Colagrossi, Marrone & Molteni
  (2010, CPC 181) and Antuono et al. (2012, CPC 183): the pair term is corrected
  by the renormalised density gradients of a and b, so it vanishes for every linear density
  field, at a free surface too (where the plain term diffuses the hydrostatic gradient);
* ``fourtakasDeltaSPH``: the hydrostatically consistent diffusion of Fourtakas, Dominguez,
  Vacondio & Rogers (2019, Computers & Fluids 190): the pair difference of the total density
  is replaced by that of its dynamic part rho^D = rho - rho^H, rho^H the density of the
  hydrostatic pressure of the pair's depth difference.

Both add to drho_a/dt at every evaluation of the rates (no periodic pass); the pair terms are
antisymmetric in a and b, so sum_a V_a drho_a is unchanged by them.
"""

from __future__ import annotations

import math

import numpy as np
from pydantic import Field

from sphfoam.engine.terms import Term
from sphfoam.models.base import CaseContext
from sphfoam.models.filters import WALLS_DOC, DensityFilter, diffusion_sees
from sphfoam.registry import Coeffs, register

#: |y| up to which the hydrostatic density differences below are the binomial series (a
#: polynomial the pair code evaluates inline, Horner in y^2 or x). For a = 1/gamma in (0, 1],
#: |C(a, k)| <= a / k, so the first omitted term of either series is below y^12 / 13 = 2e-17
#: of the first: exact to round-off, and more accurate than the difference of two powers near
#: 1 it replaces. A case whose pairs reach beyond it (a coarse resolution with a slow speed of
#: sound) gets the polynomial of the same degree interpolating the closed form at the Chebyshev
#: points of its own range (:func:`hydrostatic_coefficients`).
SERIES_Y = 0.05
#: the terms kept: y^1 ... y^11 (midpoint, odd), x^1 ... x^12 (particle)
SERIES_K = 12
#: the relative accuracy the polynomial must keep over the case's range
SERIES_TOL = 1e-12


def binomials(a: float, kmax: int = SERIES_K) -> list[float]:
    """C(a, k) = a (a - 1) ... (a - k + 1) / k! for k = 0 ... kmax."""
    out, c = [1.0], 1.0
    for k in range(1, kmax + 1):
        c *= (a - (k - 1)) / k
        out.append(c)
    return out


def hydrostatic_closed(form: str, a: float, v):
    """The closed forms, through expm1 and log1p (no cancellation near 0): midpoint
    (1 + y)^a - (1 - y)^a, particle 1 - (1 - x)^a."""
    v = np.asarray(v, dtype=float)
    if form == "midpoint":
        return np.expm1(a * np.log1p(v)) - np.expm1(a * np.log1p(-v))
    return -np.expm1(a * np.log1p(-v))


def hydrostatic_polynomial(form: str, coeffs, v):
    """The polynomial the pair code evaluates, in the same order: midpoint
    y (s1 + y^2 (s3 + ...)), particle x (d1 + x (d2 + ...))."""
    v = np.asarray(v, dtype=float)
    t = v * v if form == "midpoint" else v
    acc = np.full_like(v, coeffs[-1])
    for c in coeffs[-2::-1]:
        acc = c + t * acc
    return v * acc


def hydrostatic_coefficients(form: str, a: float, reach: float) -> list[float]:
    """The coefficients of the hydrostatic density difference's polynomial for arguments
    |y| (midpoint) or |x| (particle) up to ``reach``: the binomial series, s_k = 2 C(a, k)
    (k odd) or d_k = (-1)^(k+1) C(a, k), where ``reach`` <= SERIES_Y; beyond, the
    polynomial of the same form interpolating the closed form at the Chebyshev points of
    [0, reach^2] (midpoint, in y^2) or [-reach, reach] (particle). Refused (ValueError) where
    it is not within SERIES_TOL of the closed form over the range."""
    c = binomials(a)
    if form == "midpoint":
        coeffs = [2.0 * c[k] for k in range(1, SERIES_K, 2)]
    else:
        coeffs = [(-1.0) ** (k + 1) * c[k] for k in range(1, SERIES_K + 1)]
    if reach <= SERIES_Y:
        return coeffs
    n = len(coeffs)
    cheb = np.cos(np.pi * (np.arange(n) + 0.5) / n)
    P = np.polynomial.polynomial
    with np.errstate(all="ignore"):   # (1 - x)^a has no real value past x = 1: refused below
        if form == "midpoint":
            t = 0.5 * reach * reach * (1.0 + cheb)
            v = np.sqrt(t)
            s = t
        else:
            v = reach * cheb
            s = v
        f = hydrostatic_closed(form, a, v) / v
        coeffs = P.polyfit(s, f, n - 1) if np.isfinite(f).all() else np.full(n, np.nan)
        v = np.linspace(-reach, reach, 4001)
        v = v[np.abs(v) > 1e-3 * reach]
        exact = hydrostatic_closed(form, a, v)
        err = float(np.max(np.abs(hydrostatic_polynomial(form, coeffs, v) - exact)
                           / np.abs(exact)))
    if not err <= SERIES_TOL:
        depth = reach if form == "particle" else 2 * reach
        raise ValueError(
            "constant/sphProperties: densityFilter fourtakasDeltaSPH: over the kernel support "
            f"the pair's hydrostatic pressure difference reaches {depth:.3g} C_B (C_B = c0^2 "
            f"rho0 / gamma), beyond what its {form} form's polynomial follows to "
            f"{SERIES_TOL:g}: the speed of sound is too slow for it (equationOfState: raise "
            "speedOfSound, or vmax or densityVariation)"
            + ("; or use reference midpoint" if form == "particle" else ""))
    return [float(x) for x in coeffs]


def _dc0(name: str, delta: float, ctx: CaseContext) -> float:
    if not ctx.c0 > 0.0:
        raise ValueError(f"{name} needs the reference speed of sound c0 > 0 (CaseContext.c0)")
    return delta * ctx.c0


class _Delta(Coeffs):
    delta: float = Field(0.1, ge=0.0, description="dimensionless diffusion coefficient delta "
                         "(0.1 in Antuono et al. 2010 and Fourtakas et al. 2019)")


@register
class AntuonoDeltaSPH(DensityFilter):
    """delta-SPH with the renormalised density gradient, Antuono et al. (2010):

        drho_a/dt += delta h c0 sum_b psi_ab . grad_a W_ab V_b,
        psi_ab = 2 (rho_b - rho_a) r_ba / |r_ba|^2 - (<grad rho>^L_a + <grad rho>^L_b),
        <grad rho>^L_a = L_a sum_b (rho_b - rho_a) grad_a W_ab V_b,
        L_a = (sum_b grad_a W_ab (x) r_ba V_b)^-1,

    r_ba = r_b - r_a, V_b = m_b / rho_b. For a linear field rho_b - rho_a = g . r_ba and the
    renormalised gradient is exactly g (wherever L_a exists, a truncated support included), so
    psi_ab . r_ba = 0 and, grad_a W_ab being parallel to r_ab, every pair term vanishes. The
    pre-pass (term ``renormalisedDensityGradient``) stores <grad rho>^L in ``aux`` for every
    particle; its sums run over every neighbour (as XSPH's, with which it shares the pre-pass
    loop; a dry wall particle enters with its own density), the diffusion's over fluid,
    ghosts and wet walls. In 3-D the same equations hold with M 3 x 3 (solved by its
    adjugate) and the gradient's three components. Guard: where det M / (M_xx M_yy) (M_xx
    M_yy M_zz in 3-D; Hadamard's ratio, 1 for a full symmetric support) is below ``minDetRatio`` (an isolated or nearly isolated particle) the gradient is
    set to zero, i.e. that particle's pairs fall back to the Molteni & Colagrossi term. No
    eta^2 guard on |r|^2 (it would spoil the exactness; the pair loop has r2 > 0 and the ratio
    (rho_b - rho_a) / |r| stays bounded for a smooth field).
    """

    name = "antuonoDeltaSPH"
    doc = ("renormalised delta-SPH, Antuono et al. (2010): psi_ab = "
           "2(rho_b-rho_a) r_ba/r^2 - (<grad rho>^L_a + <grad rho>^L_b), exact for linear rho")

    class Coeffs(_Delta):
        minDetRatio: float = Field(1e-3, gt=0.0, lt=1.0, description=(
            "a particle whose matrix sum_b grad W (x) r_ba V_b has det M < minDetRatio M_xx "
            "M_yy (Hadamard's bound) gets a zero renormalised gradient (plain delta-SPH)"))

    _INIT = """\
filt_mxx = 0.0
filt_mxy = 0.0
filt_myx = 0.0
filt_myy = 0.0
filt_sx = 0.0
filt_sy = 0.0
"""
    # M = sum_b grad_a W_ab (x) r_ba V_b, r_ba = -r_ab; s = sum_b (rho_b - rho_a) grad_a W_ab V_b
    _PAIR = """\
filt_vb = mb / rhob
filt_mxx -= gWx * dx_ab * filt_vb
filt_mxy -= gWx * dy_ab * filt_vb
filt_myx -= gWy * dx_ab * filt_vb
filt_myy -= gWy * dy_ab * filt_vb
filt_drb = (rhob - rhoa) * filt_vb
filt_sx += filt_drb * gWx
filt_sy += filt_drb * gWy
"""
    # s = M g for a linear field (s_i = sum_b g_j r_ba,j gW_i V_b = M_ij g_j): g = M^-1 s
    _FINAL = """\
filt_det = filt_mxx * filt_myy - filt_mxy * filt_myx
filt_had = abs(filt_mxx * filt_myy)
if filt_had > 0.0 and abs(filt_det) > filt_min_det * filt_had:
    aux[I_rgrad_x, a] = (filt_myy * filt_sx - filt_mxy * filt_sy) / filt_det
    aux[I_rgrad_y, a] = (filt_mxx * filt_sy - filt_myx * filt_sx) / filt_det
else:
    aux[I_rgrad_x, a] = 0.0
    aux[I_rgrad_y, a] = 0.0
"""
    # psi_ab . grad_a W_ab with r_ba = -r_ab: 2 (rho_a - rho_b) r_ab.gradW / r^2 - (G_a+G_b).gradW
    _DIFFUSION = """\
filt_psi = 2.0 * (rhoa - rhob) * dot(d@_ab, gW@) / r2 \\
    - dot(aux[I_rgrad_@, a] + aux[I_rgrad_@, b], gW@)
drho_a += filt_dc0 * h * filt_psi * mb / rhob
"""

    #: 3-D: M is 3 x 3 and g = M^-1 s by its adjugate (C_ji the cofactors), the Hadamard
    #: ratio |det M| / |M_xx M_yy M_zz|; the same equations of Antuono et al. (2010) in d = 3
    _INIT_3D = "".join(f"filt_m{i}{j} = 0.0\n" for i in "xyz" for j in "xyz") + \
        "".join(f"filt_s{i} = 0.0\n" for i in "xyz")
    _PAIR_3D = "filt_vb = mb / rhob\n" + "".join(
        f"filt_m{i}{j} -= gW{i} * d{j}_ab * filt_vb\n" for i in "xyz" for j in "xyz") + \
        "filt_drb = (rhob - rhoa) * filt_vb\n" + "".join(
            f"filt_s{i} += filt_drb * gW{i}\n" for i in "xyz")

    @staticmethod
    def _final_3d() -> str:
        ax = "xyz"

        def m(i, j):
            return f"filt_m{ax[i % 3]}{ax[j % 3]}"

        lines = [f"filt_c{ax[i]}{ax[j]} = {m(i + 1, j + 1)} * {m(i + 2, j + 2)} - "
                 f"{m(i + 1, j + 2)} * {m(i + 2, j + 1)}" for i in range(3) for j in range(3)]
        lines.append("filt_det = filt_mxx * filt_cxx + filt_mxy * filt_cxy + filt_mxz * filt_cxz")
        lines.append("filt_had = abs(filt_mxx * filt_myy * filt_mzz)")
        lines.append("if filt_had > 0.0 and abs(filt_det) > filt_min_det * filt_had:")
        for i in range(3):
            lines.append(f"    aux[I_rgrad_{ax[i]}, a] = (" + " + ".join(
                f"filt_c{ax[j]}{ax[i]} * filt_s{ax[j]}" for j in range(3)) + ") / filt_det")
        lines.append("else:")
        lines += [f"    aux[I_rgrad_{c}, a] = 0.0" for c in ax]
        return "\n".join(lines) + "\n"

    def params(self, ctx: CaseContext):
        return {"filt_dc0": _dc0(self.name, self.coeffs.delta, ctx),
                "filt_min_det": self.coeffs.minDetRatio}

    def terms(self):
        g = ("aux.rgrad_@",)          # rgrad_x, rgrad_y (2-D), rgrad_z (3-D)
        return [Term("renormalisedDensityGradient", ("prepass",),
                     init={2: self._INIT, 3: self._INIT_3D},
                     pair={2: self._PAIR, 3: self._PAIR_3D},
                     final={2: self._FINAL, 3: self._final_3d()}, applies=("all",),
                     sees=("all",), reads=("gradW",), writes=g),
                Term("densityDiffusion", ("rates", "density"),
                     pair=self._DIFFUSION,
                     reads=("gradW", *g), writes=("drho",))]


@register
class FourtakasDeltaSPH(DensityFilter):
    """Hydrostatically consistent density diffusion of Fourtakas et al. (2019) (the form
    DualSPHysics documents as "Fourtakas et al. 2019"):

        drho_a/dt += 2 delta h c0 sum_b (rho^D_a - rho^D_b) r_ab . grad_a W_ab / |r_ab|^2 V_b,
        rho^D_a - rho^D_b = (rho_a - rho_b) - (rho^H_a - rho^H_b),

    i.e. the Molteni & Colagrossi term of the dynamic density rho^D = rho - rho^H. The
    hydrostatic part comes from the hydrostatic pressure difference of the pair,
    p^H_a - p^H_b = rho0 g . r_ab (g the gravity vector, so rho0 g (z_b - z_a) for gravity
    -g e_z), through the Tait equation of state T(3.27) inverted, rho = rho0 (1 + p/C_B)^(1/gamma),
    C_B = c0^2 rho0 / gamma:

    * ``reference midpoint`` (default): both pressures taken about the pair's mid-depth,
      rho^H_a - rho^H_b = rho0 ((1 + x/2)^(1/gamma) - (1 - x/2)^(1/gamma)), x = rho0 g . r_ab / C_B;
      odd in r_ab, so the pair term is antisymmetric and sum_a V_a drho_a = 0 exactly;
    * ``reference particle``: the paper's form, a's pressure as the reference,
      rho^H_ba = rho0 ((1 + rho0 g z_ab / C_B)^(1/gamma) - 1); not odd in r_ab for gamma != 1
      (its mass rate is of second order in x).

    Both agree to first order in x (x ~ dx / (gamma H) is small) and are exact for gamma = 1
    (the linear equation of state). Both take the pressures about p = 0, so the difference is
    the hydrostatic one at the free surface: in a fluid at hydrostatic rest rho^D is uniform
    to first order, so the term vanishes at the free surface and the bottom too, where the
    plain term diffuses the hydrostatic gradient across the truncated support and drives a
    spurious flow. What it leaves (gamma > 1) is the Tait column's curvature, whose slope
    falls with depth as (rho/rho0)^(1 - gamma): D/rho = delta h c0 rho''/rho, rho''/rho =
    -(gamma - 1) (g/c0^2)^2 (1 + gamma g d / c0^2)^-2 at depth d (checked with
    ``benchmarks/packing.py --budget`` in tests/test_solitary.py; its size against the
    packing drift's in docs/low-dissipation.md). ``gamma`` must be the equation of state's
    exponent (7 for the Tait default, 1 for a linear law). Wall particles are neighbours
    with their own density and get no diffusion themselves (``walls yes``); ``walls no``
    keeps the term within the fluid (and mirrored ghosts): see ``deltaSPH``.
    """

    name = "fourtakasDeltaSPH"
    doc = ("hydrostatic-consistent delta-SPH, Fourtakas et al. (2019): diffusion of rho^D = "
           "rho - rho^H, rho^H from rho0 g z_ab via Tait T(3.27), C_B = c0^2 rho0/gamma")

    class Coeffs(_Delta):
        gamma: float = Field(7.0, ge=1.0, description=(
            "exponent of the equation of state that turns the hydrostatic pressure into "
            "density (the Tait gamma, 7 by default; 1 for a linear equation of state)"))
        reference: str = Field("midpoint", pattern="^(midpoint|particle)$", description=(
            "midpoint: the pair's hydrostatic density difference about its mid-depth "
            "(antisymmetric, conserves mass); particle: the paper's form with a as reference"))
        walls: bool = Field(True, description=WALLS_DOC)

    #: rho^H_a - rho^H_b = rho0 y P(y^2), y = x / 2 (:func:`hydrostatic_coefficients`), in
    #: the loop (a call with a branch to the powers costs as much as the rest of the loop)
    _MIDPOINT = """\
filt_y = 0.5 * (filt_rho0_cb * dot(g@, d@_ab))
filt_y2 = filt_y * filt_y
filt_dh = filt_rho0 * (filt_y * (filt_s1 + filt_y2 * (filt_s3 + filt_y2 * (filt_s5 + filt_y2 * (
    filt_s7 + filt_y2 * (filt_s9 + filt_y2 * filt_s11))))))
filt_psi = 2.0 * (rhoa - rhob - filt_dh) * dot(d@_ab, gW@) / (r2 + eta2)
drho_a += filt_dc0 * h * filt_psi * mb / rhob
"""
    _PARTICLE = """\
filt_x = filt_rho0_cb * dot(g@, d@_ab)
filt_dh = filt_rho0 * (filt_x * (filt_d1 + filt_x * (filt_d2 + filt_x * (filt_d3 + filt_x * (
    filt_d4 + filt_x * (filt_d5 + filt_x * (filt_d6 + filt_x * (filt_d7 + filt_x * (
        filt_d8 + filt_x * (filt_d9 + filt_x * (filt_d10 + filt_x * (filt_d11 + filt_x * (
            filt_d12)))))))))))))
filt_psi = 2.0 * (rhoa - rhob - filt_dh) * dot(d@_ab, gW@) / (r2 + eta2)
drho_a += filt_dc0 * h * filt_psi * mb / rhob
"""

    def params(self, ctx: CaseContext):
        dc0 = _dc0(self.name, self.coeffs.delta, ctx)
        gamma = self.coeffs.gamma
        cb = ctx.c0 * ctx.c0 * ctx.rho0 / gamma
        form = self.coeffs.reference
        # the largest |x| = rho0 |g . r_ab| / C_B over the kernel support (3 h, the widest
        # registered kernel's, where the context does not give it)
        reach = ctx.rho0 / cb * math.hypot(*ctx.g) * (ctx.support or 3.0 * ctx.h)
        if form == "midpoint":
            c = hydrostatic_coefficients(form, 1.0 / gamma, 0.5 * reach)
            series = {f"filt_s{k}": v for k, v in zip(range(1, SERIES_K, 2), c)}
        else:
            c = hydrostatic_coefficients(form, 1.0 / gamma, reach)
            series = {f"filt_d{k}": v for k, v in zip(range(1, SERIES_K + 1), c)}
        return {"filt_dc0": dc0, "filt_rho0": ctx.rho0, "filt_rho0_cb": ctx.rho0 / cb,
                **series}

    #: the midpoint form's term for the pair (b, a): rho^H is odd in r_ab and
    #: r_ba . grad_b W_ba = r_ab . grad_a W_ab, so psi_ba = -psi_ab (half lists)
    _MIDPOINT_REACTION = """\
filt_y_b = 0.5 * (filt_rho0_cb * dot(g@, d@_ab))
filt_y2_b = filt_y_b * filt_y_b
filt_dh_b = filt_rho0 * (filt_y_b * (filt_s1 + filt_y2_b * (filt_s3 + filt_y2_b * (
    filt_s5 + filt_y2_b * (filt_s7 + filt_y2_b * (filt_s9 + filt_y2_b * filt_s11))))))
filt_psi_b = 2.0 * (rhoa - rhob - filt_dh_b) * dot(d@_ab, gW@) / (r2 + eta2)
drho_b -= filt_dc0 * h * filt_psi_b * ma / rhoa
"""

    def terms(self):
        mid = self.coeffs.reference == "midpoint"
        return [Term("hydrostaticDensityDiffusion", ("rates", "density"),
                     pair=self._MIDPOINT if mid else self._PARTICLE,
                     reaction=self._MIDPOINT_REACTION if mid else "",
                     reads=("gradW",), writes=("drho",), **diffusion_sees(self.coeffs.walls))]
