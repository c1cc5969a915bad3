"""Solitary-wave theories (``waveTheory`` family): the registered theories a case selects.

Each returns a :class:`~sphfoam.reference.solitary.SolitaryWave` (surface, velocity, pressure,
celerity); the solutions themselves, and their conventions, are in
:mod:`sphfoam.reference.solitary`.
"""

from __future__ import annotations

from pydantic import Field

from sphfoam.reference.solitary import (BoussinesqWave, EulerWave, FentonWave, KdV1Wave, KdV2Wave,
                                       LaitoneWave, McCowanWave, SolitaryWave)
from sphfoam.registry import Coeffs, Model, register


# --- registered theories ----------------------------------------------------------------------
class WaveTheory(Model):
    """Base of the solitary-wave theories: ``solitary(A, d, g)`` returns a :class:`SolitaryWave`
    with vectorised ``eta``, ``u``, ``w``, ``p``, celerity ``c`` and ``volume()``."""

    family = "waveTheory"
    Wave: type[SolitaryWave] = SolitaryWave

    class Coeffs(Coeffs):
        rho: float = Field(1000.0, gt=0, description="water density (kg/m^3) for the pressure")

    def solitary(self, A: float, d: float, g: float = 9.81) -> SolitaryWave:
        """The wave of height A (m) in depth d (m) under gravity g (m/s^2)."""
        return self.Wave(A, d, g, rho=self.coeffs.rho)


@register
class Boussinesq(WaveTheory):
    """Boussinesq's (1872) first-order solitary wave: eta = A sech^2(kappa (x - c t)),
    kappa = sqrt(3A/(4 d^3)), c = sqrt(g (d + A)) and a depth-uniform u = c eta/(d + eta); the
    vertical velocity w = -z du/dx follows from continuity and the pressure is hydrostatic
    below the local surface (the theory gives neither)."""

    name = "boussinesq"
    doc = "Boussinesq first-order solitary wave, T(4.1)-(4.5)"
    Wave = BoussinesqWave


@register
class McCowan(WaveTheory):
    """McCowan's (1891) solitary wave (Munk 1949): implicit surface T(4.6), celerity
    c^2 = g d tan(M)/M, depth-dependent u and w T(4.8)-(4.9) with z from the bed, M and N from
    T(4.10)-(4.11) solved to machine precision; the pressure is hydrostatic below the local
    surface (the theory gives none)."""

    name = "mcCowan"
    doc = "McCowan solitary wave, T(4.6)-(4.11)"
    Wave = McCowanWave


@register
class Laitone(WaveTheory):
    """Laitone's (1960) second-order solitary wave: surface T(4.12)-(4.13), celerity
    c = sqrt(g d)(1 + A/(2d) - 3/20 (A/d)^2), u T(4.15) and w = -sqrt(g d)(z/d) d(eta)/dX
    T(4.16) with z from the bed; the pressure is hydrostatic below the local surface (the
    thesis gives none; ``kdv2`` is the same wave with the full second-order w and p)."""

    name = "laitone"
    doc = "Laitone second-order solitary wave, T(4.12)-(4.16)"
    Wave = LaitoneWave


@register
class KdV1(WaveTheory):
    """First-order KdV solitary wave (Wehausen & Laitone 1960) as in P(6)-(11):
    eta = A sech^2 zeta, u = sqrt(g d) eta/d, w linear in z, hydrostatic pressure P(9),
    c = sqrt(g d)(1 + A/(2d))."""

    name = "kdv1"
    doc = "first-order KdV solitary wave with u, w, p, P(6)-(11)"
    Wave = KdV1Wave


@register
class KdV2(WaveTheory):
    """Second-order KdV solitary wave (Wehausen & Laitone 1960) as in P(12)-(17): surface,
    velocities and the second-order dynamic pressure P(15), c = sqrt(g d)(1 + A/(2d) -
    3/20 (A/d)^2)."""

    name = "kdv2"
    doc = "second-order KdV solitary wave with u, w, p, P(12)-(17)"
    Wave = KdV2Wave


@register
class Fenton(WaveTheory):
    """Fenton's (1972) ninth-order solitary wave: eta = d sum_{i<=9} eps^i sum_j a_ij S^j with
    S = sech^2(alpha x/d), alpha = sqrt(3 eps/4)(1 - 5/8 eps + 71/128 eps^2 - ...), u and w from
    the stream function of the bed velocity, Bernoulli's pressure, c/sqrt(g d) = 1 + eps/2 -
    3/20 eps^2 + 3/56 eps^3 - 309/5600 eps^4 + ...; the series is asymptotic, best for
    A/d <~ 0.5 (c within 4e-5 of the exact wave there)."""

    name = "fenton"
    doc = "Fenton (1972) ninth-order solitary wave, eta/u/w/p series in sech^2 (coefficients " \
          "re-derived by his scheme)"
    Wave = FentonWave


@register
class Euler(WaveTheory):
    """The exact solitary wave of the Euler equations (irrotational, inviscid): Bernoulli and
    kinematic surface conditions solved to 1e-13 in the conformal plane (Clamond & Dutykh
    2013, eqs. 2.6-2.8) by Newton's method with continuation in A/d, once per A/d (cached);
    eta, u, w, p anywhere in the fluid from the conformal map, the pressure from Bernoulli;
    celerity as Longuet-Higgins & Fenton (1974) and Tanaka (1986); A/d <= 0.78."""

    name = "euler"
    doc = "exact (fully nonlinear) Euler solitary wave, conformal-map Newton solution " \
          "(Clamond & Dutykh 2013 eqs 2.6-2.8)"
    Wave = EulerWave
