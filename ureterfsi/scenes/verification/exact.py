"""Exact solutions the engine is checked against: annular Poiseuille flow, plane-strain inflation of an
incompressible five-parameter Mooney-Rivlin tube, a bar and a confined column under their own weight (SI units)."""
from __future__ import annotations

import math

import numpy as np
from scipy.optimize import brentq

from ureterfsi.fsi import MooneyRivlin


def annular_poiseuille_velocity(r, R1, R2, G, mu, log=np.log):
    """Axial velocity of steady flow between coaxial cylinders R1 < r < R2, no slip on both, driven by
    the pressure gradient -dp/dz = G > 0 (flow towards +z):
        mu (1/r) d/dr (r dv/dr) = -G,  v(R1) = v(R2) = 0
        v(r) = G/(4 mu) [R2^2 - r^2 + (R2^2 - R1^2) ln(r/R2) / ln(R2/R1)].
    `log` = ufl.ln gives the UFL expression of a SpatialCoordinate component."""
    return G / (4.0 * mu) * (R2**2 - r**2 + (R2**2 - R1**2) * log(r / R2) / math.log(R2 / R1))


def annular_poiseuille_flux(R1, R2, G, mu):
    """Q = int_R1^R2 2 pi r v dr = pi G/(8 mu) [R2^4 - R1^4 - (R2^2 - R1^2)^2 / ln(R2/R1)]."""
    return math.pi * G / (8.0 * mu) * (R2**4 - R1**4 - (R2**2 - R1**2) ** 2 / math.log(R2 / R1))


def annular_poiseuille_wall_shear(r, R1, R2, G, mu):
    """|tau_w| = mu |dv/dr| of annular Poiseuille flow on the wall r = R1 or R2:
    dv/dr = G/(4 mu) [-2 r + (R2^2 - R1^2) / (r ln(R2/R1))]."""
    return 0.25 * G * abs(-2.0 * r + (R2**2 - R1**2) / (r * math.log(R2 / R1)))


def mooney_rivlin_plane_strain_stress_difference(lam, mat: MooneyRivlin):
    """sigma_theta - sigma_r = lam dW/dlam for the incompressible plane-strain inflation, lam = r/R the hoop
    stretch (principal stretches 1/lam, lam, 1). Plane strain gives I1 = I2 = lam^2 + lam^-2 + 1, so
    W = c1 (I - 3) + c2 (I - 3)^2 with c1 = C10 + C01, c2 = C20 + C02 + C11, I - 3 = (lam - 1/lam)^2."""
    c1, c2 = mat.c10 + mat.c01, mat.c20 + mat.c02 + mat.c11
    s = (lam - 1.0 / lam) ** 2
    return (c1 + 2.0 * c2 * s) * (2.0 * lam**2 - 2.0 / lam**2)


def mooney_rivlin_tube_pressure(ri, Ri, Ro, mat: MooneyRivlin):
    """Internal (Cauchy, deformed-configuration) pressure that inflates the incompressible tube to inner
    radius ri in plane strain: r^2 = R^2 + (ri^2 - Ri^2); radial equilibrium d sigma_r/dr = (sigma_t - sigma_r)/r
    with sigma_r(ri) = -p, sigma_r(ro) = 0 gives p = int_ri^ro (sigma_t - sigma_r) dr / r
    = int_Ri^Ro (sigma_t - sigma_r)(lam) R / r^2 dR (r dr = R dR)."""
    a = ri**2 - Ri**2
    # the integrand is smooth on [Ri, Ro]: 64-point Gauss-Legendre is exact to rounding
    xi, wq = np.polynomial.legendre.leggauss(64)
    R = 0.5 * (Ro - Ri) * xi + 0.5 * (Ro + Ri)
    r2 = R * R + a
    f = mooney_rivlin_plane_strain_stress_difference(np.sqrt(r2) / R, mat) * R / r2
    return float(0.5 * (Ro - Ri) * np.dot(wq, f))


def mooney_rivlin_tube_inner_radius(Ri, Ro, mat: MooneyRivlin, pressure=None, dead_load=None):
    """Deformed inner radius r_i of the plane-strain tube under either a follower `pressure` p (Cauchy,
    on the deformed surface) or a radial `dead_load` p0 per reference area (P N = -p0 N on the inner
    surface). By symmetry the dead load stays radial, and per unit length p0 Ri dTheta = p ri dtheta,
    so it equals the follower pressure p = p0 Ri / ri; both are found by Brent's method."""
    if (pressure is None) == (dead_load is None):
        raise ValueError("give exactly one of pressure, dead_load")
    if pressure is not None:
        f = lambda ri: mooney_rivlin_tube_pressure(ri, Ri, Ro, mat) - pressure  # noqa: E731
    else:
        f = lambda ri: mooney_rivlin_tube_pressure(ri, Ri, Ro, mat) - dead_load * Ri / ri  # noqa: E731
    return brentq(f, Ri * (1.0 + 1e-12), 3.0 * Ri, xtol=1e-15 * Ri, rtol=1e-14)




def hanging_bar_displacement(z, length, weight, youngs_modulus):
    """Axial displacement of a linear elastic bar (nu = 0) held at z = 0, free at z = L, under a body force
    `weight` b per volume along +z: E u_z'' = -b, u_z(0) = 0, u_z'(L) = 0 -> u_z = b (L z - z^2/2) / E, with
    sigma_zz = b (L - z) the only stress and u_x = u_y = u_r = 0: the exact 3D (and axisymmetric) solution."""
    return weight * (length * z - 0.5 * z**2) / youngs_modulus




def mooney_rivlin_uniaxial_strain_stress(lam, mat: MooneyRivlin):
    """Nominal stress P_zz of the engine's Mooney-Rivlin law in uniaxial strain F = diag(1, 1, lam), J = lam:
    I1 = 2 + lam^2, I2 = 1 + 2 lam^2, P_zz = dW_iso/dlam + kappa (lam - 1) (the P0 pressure pi = kappa (J - 1))."""
    lam = np.asarray(lam, dtype=float)
    i1, i2 = lam ** (-2.0 / 3.0) * (2.0 + lam**2) - 3.0, lam ** (-4.0 / 3.0) * (1.0 + 2.0 * lam**2) - 3.0
    di1 = -2.0 / 3.0 * lam ** (-5.0 / 3.0) * (2.0 + lam**2) + 2.0 * lam ** (1.0 / 3.0)
    di2 = -4.0 / 3.0 * lam ** (-7.0 / 3.0) * (1.0 + 2.0 * lam**2) + 4.0 * lam ** (-1.0 / 3.0)
    w1 = mat.c10 + 2.0 * mat.c20 * i1 + mat.c11 * i2
    w2 = mat.c01 + 2.0 * mat.c02 * i2 + mat.c11 * i1
    return w1 * di1 + w2 * di2 + mat.bulk_modulus * (lam - 1.0)


def confined_column_top_displacement(length, weight, mat: MooneyRivlin):
    """Top displacement of a column 0 < Y < L in a frictionless rigid channel (lateral displacement zero), held
    at Y = 0, under a body force `weight` b per reference volume along +Y. Uniaxial strain F = diag(1, 1, lam(Y))
    for any isotropic law: dP/dY = -b, P(L) = 0 -> P(lam(Y)) = b (L - Y), and u(L) = int_0^L (lam - 1) dY
    (64-point Gauss-Legendre on the smooth integrand, Brent's method for lam)."""
    xi, wq = np.polynomial.legendre.leggauss(64)
    Y = 0.5 * length * (xi + 1.0)
    lam = [brentq(lambda s, P=weight * (length - y): mooney_rivlin_uniaxial_strain_stress(s, mat) - P,
                  0.2, 5.0, xtol=1e-15, rtol=1e-15) for y in Y]
    return float(0.5 * length * np.dot(wq, np.asarray(lam) - 1.0))
