"""The Dirichlet-to-Neumann operator of a periodic free surface over a flat bed, by a boundary
integral (Cauchy's formula): W, the vertical velocity at the surface, from eta(x) and the
surface potential psi(x) = phi(x, eta(x)), without the HOS method's expansion about z = 0.

Units g = d = 1, the bed at y = -1, a periodic domain of length L sampled at N equidistant
x_k (the fixed grid of the Zakharov time-stepper in :mod:`sphfoam.reference.wall_reflection`).

Equations. The complex potential beta = phi + i chi (chi the stream function) is analytic in
the fluid; the bed is a streamline, chi = 0 there, so by Schwarz's reflection beta extends to
the image of the fluid about y = -1 with beta(conj(z) - 2i) = conj(beta(z)). The doubled
domain is the periodic strip between the surface C, z(x) = x + i eta(x), and its image C',
z'(x) = x - i (2 + eta(x)), on which beta' = phi - i chi. Cauchy's formula with the periodic
kernel K(s) = (pi/L) cot(pi s / L), taken counter-clockwise (C' in +x, C in -x; the sides
x = +-L/2 cancel by periodicity), reads at a surface node z_j

    pi i beta(z_j) = int_C' conj(beta) K(z' - z_j) z'_x dx  -  PV int_C beta K(z - z_j) z_x dx

(the method of Vinje & Brevig 1981, Adv. Water Resour. 4, and of Dold 1992, J. Comput. Phys.
103, for the Cauchy-integral water-wave problem; the image of the bed as in Dold's
finite-depth form). The principal-value integral along C is discretised with the
alternate-point trapezoidal rule of Sidi & Israeli (1988, J. Sci. Comput. 3: only nodes k
with k - j odd, weight 2 dx; spectrally accurate for a periodic integrand with a simple
pole), the regular integral along C' (at least 2 + 2 min(eta) below the node) with the plain
trapezoidal rule; z_x = 1 + i eta_x by spectral differentiation. With phi = psi known, the
real part of the equation is a second-kind equation for chi at the N nodes,

    pi chi_j + sum_k dx Im(A'_jk) chi_k + sum_{k-j odd} 2 dx Im(A_jk) chi_k
        = -sum_k dx Re(A'_jk) psi_k + sum_{k-j odd} 2 dx Re(A_jk) psi_k,

A_jk = K(z_k - z_j) z_x(x_k), A'_jk = K(z'_k - z_j) z'_x(x_k), solved densely
(numpy.linalg.solve). There is no nullspace: a constant chi = c would have the value -c on
C' (the image flips its sign), so the operator maps it to about 2 pi c; the mean of chi is
fixed, as chi = 0 on the bed requires (checked in tests against known fields). Then along
the surface d beta / dx = psi_x + i chi_x and d beta / dz = u - i w, so

    u - i w = (psi_x + i chi_x) / (1 + i eta_x),     W = w.

The kernel is evaluated without a transcendental function per matrix entry:
cot(pi (z_k - z_j) / L) = i (q + 1) / (q - 1) with q = E_k / E_j, E = exp(2 pi i z / L).

For a surface even about x = 0 (eta and psi even, so chi odd) :meth:`stream_function`
with ``even=True`` solves for chi at x > 0 only (N/2 - 1 unknowns, chi = 0 at x = 0 and
x = L/2), an eighth of the full solve's cost.
"""

from __future__ import annotations

import math

import numpy as np


class DirichletToNeumann:
    """W = phi_y at the surface of the periodic domain [-L/2, L/2) with N nodes
    x_k = (k - N/2) L/N (x = 0 at k = N/2), depth 1 below y = 0."""

    def __init__(self, L: float, N: int):
        if N % 2:
            raise ValueError(f"N must be even (alternate-point quadrature), got {N}")
        self.L, self.N = float(L), int(N)
        self.dx = self.L / self.N
        self.x = (np.arange(N) - N // 2) * self.dx
        k = 2.0 * math.pi * np.fft.rfftfreq(N, self.dx)
        self.ik = 1j * k
        self.ik[-1] = 0.0                      # Nyquist: a real derivative has none
        j = np.arange(N)
        self.odd = 2.0 * ((j[:, None] - j[None, :]) % 2 == 1)     # the rule's weight 2 dx
        self._pos = np.arange(N // 2 + 1, N)          # x > 0
        self._mirror = (N - self._pos) % N            # their images at -x

    def derivative(self, f):
        return np.fft.irfft(np.fft.rfft(f) * self.ik, self.N)

    def _matrices(self, eta, eta_x, rows=None):
        """G = dx K(z_k - z_j) z_x,k on C (zero where k - j is even) and G' = dx K(z'_k - z_j)
        z'_x,k on C' (rows j, all of them or ``rows``; columns k)."""
        rows = np.arange(self.N) if rows is None else rows
        c = 2.0 * math.pi / self.L
        z = self.x + 1j * eta
        E = np.exp(1j * c * z)                                    # |E| = exp(-c eta)
        q = E[None, :] / E[rows, None]
        q[np.arange(rows.size), rows] = -1.0                      # cot -> 0, masked anyway
        G = (1j * (q + 1.0) / (q - 1.0)) * (0.5 * c * self.dx) * (1.0 + 1j * eta_x)[None, :]
        G *= self.odd[rows]
        # C': Im(z'_k - z_j) = -(2 + eta_k + eta_j) < 0; with r = 1/q' (|r| < 1)
        # cot(w) = i (q' + 1)/(q' - 1) = i (1 + r)/(1 - r)
        Ep = np.exp(-1j * c * (self.x - 1j * (2.0 + eta)))       # 1 / exp(i c z')
        r = E[rows, None] * Ep[None, :]
        Gp = (1j * (1.0 + r) / (1.0 - r)) * (0.5 * c * self.dx) * (1.0 - 1j * eta_x)[None, :]
        return G, Gp

    def stream_function(self, eta, psi, eta_x=None, even: bool = False):
        """chi at the surface nodes (chi = 0 on the bed). ``even``: eta and psi are even
        about x = 0 (only their values at x >= 0 are used), chi odd."""
        eta = np.asarray(eta, float)
        psi = np.asarray(psi, float)
        if eta_x is None:
            eta_x = self.derivative(eta)
        if not even:
            G, Gp = self._matrices(eta, eta_x)
            M = Gp.imag + G.imag
            M[np.diag_indices(self.N)] += math.pi
            return np.linalg.solve(M, (G.real - Gp.real) @ psi)
        p, m = self._pos, self._mirror
        G, Gp = self._matrices(eta, eta_x, rows=p)
        M = Gp.imag + G.imag
        M[np.arange(p.size), p] += math.pi
        sol = np.linalg.solve(M[:, p] - M[:, m], (G.real - Gp.real) @ psi)
        chi = np.zeros(self.N)
        chi[p] = sol
        chi[m] = -sol
        return chi

    def vertical_velocity(self, eta, psi, even: bool = False, eta_x=None, psi_x=None):
        """W = phi_y at the surface: -Im((psi_x + i chi_x) / (1 + i eta_x))."""
        if eta_x is None:
            eta_x = self.derivative(eta)
        if psi_x is None:
            psi_x = self.derivative(psi)
        chi = self.stream_function(eta, psi, eta_x, even=even)
        chi_x = self.derivative(chi)
        return -((psi_x + 1j * chi_x) / (1.0 + 1j * eta_x)).imag
