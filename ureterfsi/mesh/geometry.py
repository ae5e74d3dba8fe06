"""Geometry of the ureter segment, the stent and its side holes (paper §2.1, Table 1).

All lengths in metres. The ureter axis is z, inlet (kidney) at z = 0, outlet (bladder) at z = L.
Side holes are radial, in diametrically opposite pairs, all on the y axis (`hole_arrangement: aligned`) or
alternating between the y and the x axis from pair to pair (`rotated_90`). The stent axis lies on the
ureter's or displaced along x by `stent_offset`. An optional axisymmetric stricture narrows the
lumen over a length; the wall keeps its thickness (`UreterGeometry.inner_radius`). A complete occlusion
(`Occlusion`) closes the annulus onto the stent over a length: the wall's inner surface lies on the stent's outer one.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

# share of the full segment a mesh symmetry models (the r-z integrals carry the weight 2 pi r: the whole)
SYMMETRY_FRACTION = {"full": 1.0, "half": 0.5, "quarter": 0.25, "axisymmetric": 1.0}


@dataclass(frozen=True)
class Stricture:
    """Axisymmetric narrowing of the lumen (config geometry.stricture_*): radius reduced by `fraction` at the
    axial centre `position`, over `length`."""
    fraction: float
    length: float
    position: float

    @classmethod
    def from_geometry(cls, g: dict) -> "Stricture":
        return cls(g["stricture_fraction"], g["stricture_length"], g["stricture_position"])

    def bump(self, z):
        """b(z) = (1 + cos(2 pi (z - z_s) / l_s)) / 2 for |z - z_s| < l_s / 2, else 0 (C1, b(z_s) = 1)."""
        s = np.minimum(np.abs(np.asarray(z, dtype=float) - self.position) / (0.5 * self.length), 1.0)
        return 0.5 * (1.0 + np.cos(math.pi * s))

    def shift(self, z, inner_radius: float):
        """Inward displacement of the wall surfaces, -R_i f b(z) (constant wall thickness)."""
        return -inner_radius * self.fraction * self.bump(z)


@dataclass(frozen=True)
class Occlusion:
    """Complete occlusion (config geometry.occlusion_*): the wall's inner surface lies on the stent's outer surface
    r_s over `length` centred at `position` (the contact, where wall and stent are tied), reached over `taper` on
    either side along R(z) = r_s + (R_i - r_s) sin(pi s / 2), s = (|z - z_o| - l / 2) / t clipped to [0, 1]: the
    wall meets the stent at a finite angle (a wedge of urine, no cusp) and joins the straight wall smoothly."""
    length: float
    position: float
    taper: float

    @classmethod
    def from_geometry(cls, g: dict) -> "Occlusion | None":
        """The configured occlusion, None when geometry.occlusion_length is 0."""
        if not g["occlusion_length"]:
            return None
        return cls(g["occlusion_length"], g["occlusion_position"], g["occlusion_taper"])

    @property
    def contact(self) -> tuple:
        """(z_o - l / 2, z_o + l / 2): where the wall lies on the stent."""
        return self.position - 0.5 * self.length, self.position + 0.5 * self.length

    @property
    def span(self) -> tuple:
        """(z_o - l / 2 - t, z_o + l / 2 + t): where the wall leaves its straight radius."""
        return self.position - 0.5 * self.length - self.taper, self.position + 0.5 * self.length + self.taper

    def taper_coordinate(self, z):
        """s = (|z - z_o| - l / 2) / t, unclipped (< 0 inside the contact)."""
        return (np.abs(np.asarray(z, dtype=float) - self.position) - 0.5 * self.length) / self.taper

    def radius(self, z, wall_radius: float, stent_radius: float):
        """R(z) = r_s + (R_i - r_s) sin(pi s / 2), s clipped to [0, 1]."""
        s = np.clip(self.taper_coordinate(z), 0.0, 1.0)
        return stent_radius + (wall_radius - stent_radius) * np.sin(0.5 * math.pi * s)


@dataclass(frozen=True)
class UreterGeometry:
    length: float
    ureter_outer_radius: float
    ureter_inner_radius: float
    stent_outer_radius: float
    stent_inner_radius: float
    hole_radius: float
    hole_end_clearance: float
    stricture: Stricture | None = None
    hole_arrangement: str = "aligned"
    stent_offset: float = 0.0
    occlusion: Occlusion | None = None

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
            stricture=Stricture.from_geometry(g),
            hole_arrangement=g["hole_arrangement"],
            stent_offset=g["stent_offset"],
            occlusion=Occlusion.from_geometry(g),
        )

    @property
    def strictured(self) -> bool:
        return self.stricture is not None and self.stricture.fraction > 0.0

    @property
    def occluded(self) -> bool:
        return self.occlusion is not None

    @property
    def obstruction(self) -> str:
        """The obstruction's kind: occlusion (complete), stricture (partial) or none."""
        return "occlusion" if self.occluded else "stricture" if self.strictured else "none"

    @property
    def obstruction_centre(self) -> float | None:
        """Axial position of the obstruction's centre (occlusion, else stricture); None without one."""
        return (self.occlusion.position if self.occluded else self.stricture.position if self.strictured else None)

    def radial_shift(self, z):
        """-R_i f b(z): how far the strictured wall (both surfaces) lies inward of the straight one at z;
        Occlusion.radius(z) - R_i under an occlusion."""
        z = np.asarray(z, dtype=float)
        if self.occluded:
            ri = self.ureter_inner_radius
            return self.occlusion.radius(z, ri, self.stent_outer_radius) - ri
        if not self.strictured:
            return np.zeros_like(z)
        return self.stricture.shift(z, self.ureter_inner_radius)

    def inner_radius(self, z):
        """Lumen radius R_i(z) = R_i (1 - f b(z)) (Stricture.bump)."""
        return self.ureter_inner_radius + self.radial_shift(z)

    def outer_radius(self, z):
        """Outer wall radius R_o(z) = R_o - R_i f b(z): the wall keeps its thickness."""
        return self.ureter_outer_radius + self.radial_shift(z)

    @property
    def narrowest_radius(self) -> float:
        """Lumen radius at the stricture centre, R_i (1 - f)."""
        return self.ureter_inner_radius * (1.0 - (self.stricture.fraction if self.strictured else 0.0))

    @property
    def probe_radius(self) -> float:
        """Radius of the stent-stress probe line, the middle of the stent wall (paper §3.1)."""
        return 0.5 * (self.stent_inner_radius + self.stent_outer_radius)

    @property
    def mirror_planes(self) -> tuple:
        """Mirror planes of the geometry: y = 0 always, x = 0 unless the stent is offset along x."""
        return ("y",) if self.stent_offset else ("x", "y")

    @property
    def symmetry(self) -> str:
        """Smallest 3D model the mirror planes allow: quarter with both, half (y >= 0) with y = 0 alone."""
        return "quarter" if len(self.mirror_planes) == 2 else "half"

    def stent_probe_points(self, z) -> np.ndarray:
        """Stent-stress probe line (x_s + r_m, 0, z): mid-wall radius r_m, plane y = 0, stent axis at x_s."""
        z = np.asarray(z, dtype=float)
        return np.c_[np.full_like(z, self.stent_offset + self.probe_radius), np.zeros_like(z), z]


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


def hole_pair_axes(geom: UreterGeometry, model: StentModel) -> np.ndarray:
    """Axis of each hole pair (0 = x, 1 = y), in the order of hole_pair_positions: all 1 for `aligned`,
    1, 0, 1, ... for `rotated_90` (pair k on the y axis for even k, on the x axis for odd k)."""
    k = np.arange(hole_pair_positions(geom, model).size)
    return np.where(k % 2 == 0, 1, 0) if geom.hole_arrangement == "rotated_90" else np.ones_like(k)


def hole_channel_volume(geom: UreterGeometry) -> float:
    """Exact volume of one radial hole channel through the stent wall.

    A cylinder of radius a along y (or x: the same volume) cut by the coaxial tube r_i <= sqrt(x^2 + y^2) <= r_o:
    V = int_{-a}^{a} int_{-w(x)}^{w(x)} [sqrt(r_o^2 - x^2) - sqrt(r_i^2 - x^2)] dz dx,
    w(x) = sqrt(a^2 - x^2); evaluated with Gauss-Legendre quadrature (smooth integrand).
    """
    a, ri, ro = geom.hole_radius, geom.stent_inner_radius, geom.stent_outer_radius
    t, w = np.polynomial.legendre.leggauss(200)
    theta = 0.5 * math.pi * t          # x = a sin(theta) removes the sqrt singularity at |x| = a
    x = a * np.sin(theta)
    integrand = 2.0 * np.sqrt(a**2 - x**2) * (np.sqrt(ro**2 - x**2) - np.sqrt(ri**2 - x**2))
    return float(np.sum(w * integrand * a * np.cos(theta)) * 0.5 * math.pi)


def _axial_integral(geom: UreterGeometry, f) -> float:
    """int_0^L f(z) dz: exact for a constant f, Gauss-Legendre on each smooth piece of a strictured or occluded f."""
    if not (geom.strictured or geom.occluded):
        return float(f(np.zeros(1))[0]) * geom.length
    if geom.occluded:
        breaks = [*geom.occlusion.span[:1], *geom.occlusion.contact, geom.occlusion.span[1]]
    else:
        st = geom.stricture
        breaks = [st.position - 0.5 * st.length, st.position + 0.5 * st.length]
    edges = [0.0, *(min(max(z, 0.0), geom.length) for z in breaks), geom.length]
    t, w = np.polynomial.legendre.leggauss(64)
    total = 0.0
    for lo, hi in zip(edges[:-1], edges[1:]):
        if hi > lo:
            total += 0.5 * (hi - lo) * float(np.sum(w * f(lo + 0.5 * (hi - lo) * (t + 1.0))))
    return total


def occluded_holes(geom: UreterGeometry, model: StentModel) -> np.ndarray:
    """Positions of the hole pairs whose mouth (z_k -+ hole radius) meets the occlusion's span (contact and tapers):
    refused (config.check_occlusion), since the wall closes a hole under the contact and a hole under a taper opens
    into a wedge of urine thinner than its own diameter."""
    z = hole_pair_positions(geom, model)
    if not geom.occluded:
        return z[:0]
    lo, hi = geom.occlusion.span
    return z[(z + geom.hole_radius > lo) & (z - geom.hole_radius < hi)]


def lumen_area(geom: UreterGeometry) -> float:
    """Area of the lumen's r-z section, int_0^L R_i(z) dz (m^2)."""
    return _axial_integral(geom, geom.inner_radius)


def subdomain_volumes(geom: UreterGeometry, model: StentModel, fraction: float = 1.0) -> dict:
    """Analytic subdomain volumes (m^3) of the full model times `fraction` (1, 1/2, 1/4):
    lumen int pi R_i(z)^2 dz, wall int pi (R_o(z)^2 - R_i(z)^2) dz."""
    L = geom.length
    ureter = _axial_integral(geom, lambda z: math.pi * (geom.outer_radius(z)**2 - geom.inner_radius(z)**2))
    lumen = _axial_integral(geom, lambda z: math.pi * geom.inner_radius(z)**2)
    if model.stent:
        tube = math.pi * (geom.stent_outer_radius**2 - geom.stent_inner_radius**2) * L
        holes = model.holes * hole_channel_volume(geom)
        stent = tube - holes
        fluid = lumen - stent
    else:
        stent, fluid = 0.0, lumen
    return {"fluid": fluid * fraction, "ureter": ureter * fraction, "stent": stent * fraction}
