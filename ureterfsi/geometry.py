"""Geometry of the ureter segment, the stent and its side holes (paper §2.1, Table 1).

All lengths in metres. The ureter axis is z, inlet (kidney) at z = 0, outlet (bladder) at z = L.
Side holes are radial, in diametrically opposite pairs on the y axis.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class UreterGeometry:
    length: float
    ureter_outer_radius: float
    ureter_inner_radius: float
    stent_outer_radius: float
    stent_inner_radius: float
    hole_radius: float
    hole_end_clearance: float

    @classmethod
    def from_config(cls, cfg: dict) -> "UreterGeometry":
        g = cfg["geometry"]
        ro = 0.5 * g["ureter_outer_diameter"]
        si = 0.5 * g["stent_inner_diameter"]
        return cls(
            length=g["length"],
            ureter_outer_radius=ro,
            ureter_inner_radius=ro - g["ureter_wall_thickness"],
            stent_outer_radius=si + g["stent_wall_thickness"],
            stent_inner_radius=si,
            hole_radius=0.5 * g["hole_diameter"],
            hole_end_clearance=g["hole_end_clearance"],
        )

    @property
    def probe_radius(self) -> float:
        """Radius of the stent-stress probe line, the middle of the stent wall (paper §3.1)."""
        return 0.5 * (self.stent_inner_radius + self.stent_outer_radius)


@dataclass(frozen=True)
class StentModel:
    """One row of Table 1."""
    name: str
    label: str
    stent: bool
    hole_pair_spacing: float
    holes: int

    @classmethod
    def from_config(cls, cfg: dict, name: str) -> "StentModel":
        m = cfg["models"][str(name)]
        return cls(str(name), m["label"], m["stent"], m["hole_pair_spacing"], m["holes"])

    @property
    def pairs(self) -> int:
        return self.holes // 2


def hole_pair_positions(geom: UreterGeometry, model: StentModel) -> np.ndarray:
    """Axial positions z_k (m) of the side-hole pairs.

    Rule (config `geometry.hole_end_clearance`): z_k = clip(k s, c, L - c), k = 0..n-1, with s the
    Table 1 pair spacing and c the end clearance. Counts are exact, interior pairs keep spacing s,
    the end pairs move inward just enough to clear the fixed end faces.
    """
    if not model.stent or model.pairs == 0:
        return np.zeros(0)
    k = np.arange(model.pairs, dtype=float)
    c = geom.hole_end_clearance
    return np.clip(k * model.hole_pair_spacing, c, geom.length - c)


def outlet_hole_position(geom: UreterGeometry, model: StentModel) -> float:
    """Axial position of the outlet-most hole pair (paper §3.4-3.5, Figs. 6-9)."""
    z = hole_pair_positions(geom, model)
    if z.size == 0:
        raise ValueError(f"model {model.name} has no side holes")
    return float(z.max())


def hole_channel_volume(geom: UreterGeometry) -> float:
    """Exact volume of one radial hole channel through the stent wall.

    A cylinder of radius a along y cut by the coaxial tube r_i <= sqrt(x^2 + y^2) <= r_o:
    V = int_{-a}^{a} int_{-w(x)}^{w(x)} [sqrt(r_o^2 - x^2) - sqrt(r_i^2 - x^2)] dz dx,
    w(x) = sqrt(a^2 - x^2); evaluated with Gauss-Legendre quadrature (smooth integrand).
    """
    a, ri, ro = geom.hole_radius, geom.stent_inner_radius, geom.stent_outer_radius
    t, w = np.polynomial.legendre.leggauss(200)
    theta = 0.5 * math.pi * t          # x = a sin(theta) removes the sqrt singularity at |x| = a
    x = a * np.sin(theta)
    integrand = 2.0 * np.sqrt(a**2 - x**2) * (np.sqrt(ro**2 - x**2) - np.sqrt(ri**2 - x**2))
    return float(np.sum(w * integrand * a * np.cos(theta)) * 0.5 * math.pi)


def subdomain_volumes(geom: UreterGeometry, model: StentModel, fraction: float = 1.0) -> dict:
    """Analytic subdomain volumes (m^3) of the full model times `fraction` (1, 1/2, 1/4)."""
    L = geom.length
    ureter = math.pi * (geom.ureter_outer_radius**2 - geom.ureter_inner_radius**2) * L
    lumen = math.pi * geom.ureter_inner_radius**2 * L
    if model.stent:
        tube = math.pi * (geom.stent_outer_radius**2 - geom.stent_inner_radius**2) * L
        holes = model.holes * hole_channel_volume(geom)
        stent = tube - holes
        fluid = lumen - stent
    else:
        stent, fluid = 0.0, lumen
    return {"fluid": fluid * fraction, "ureter": ureter * fraction, "stent": stent * fraction}
