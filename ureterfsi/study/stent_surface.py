"""Wall shear stress on the stent and the exchange through its side holes (docs/wall-shear-and-exchange.md).

The stent's fluid boundary (facet tag FLUID_STENT) is split geometrically, the mesh unchanged: each hole's wall (the
facets next to a hole, hole_index, whose normal is nearer the direction e_rho from the hole's axis than the radial
direction e_R from the stent's: |N . e_rho| > |N . e_R|), the outer surface and the lumen (the other facets, radial:
|N . e_R| > cos 45 deg, outside / inside the mid-wall radius). On each region, every step: the
area-mean wall shear stress (ureterfsi.fsi.wall_shear.WallShear); at the end: TAWSS, OSI and the area fraction whose
TAWSS is below config stent_surface.low_wss_threshold. Per hole, the net flux Q_k and the gross exchange E_k
(ureterfsi.fsi.wall_shear.ChannelFlux: the mean over the channel's sections R = const of int |u.n| da, = 1/2 the
integral of |u.n| over the hole's two openings when it is the same on each section; E_k = |Q_k| for a flow that
crosses the hole one way), their time integrals, and the hole's label: active when its gross exchange volume exceeds
stent_surface.active_hole_fraction times the mean over the modelled holes.
"""
from __future__ import annotations

import numpy as np

from ureterfsi.mesh import tags
from ..fsi.wall_shear import WallShear, WallShearHistory

RADIAL = np.cos(np.pi / 4)       # |N . e_R| above: a facet of the outer surface or the lumen
HOLE_REACH = 1.5                 # hole radii from a hole's axis within which a point is next to that hole


def hole_index(points: np.ndarray, holes, stent_offset: float, hole_radius: float) -> np.ndarray:
    """Index into `holes` ((z, side, axis 0 = x / 1 = y) each) of the hole each reference point (n x 3) lies in or
    on: on its side of the stent axis (x = stent_offset, y = 0) and within HOLE_REACH hole radii of its axis, the
    nearest such; -1 for none. (A hole's points lie within one radius of its axis: a hole wider than the lumen's
    45 deg diagonal, 2 a > sqrt(2) r_i, reaches past it.)"""
    return _nearest_hole(points, holes, stent_offset, hole_radius)[0]


def _nearest_hole(points, holes, stent_offset, hole_radius):
    """(hole_index, each point's offset from that hole's axis (n x 3; 0 for none))."""
    d = np.c_[points[:, 0] - stent_offset, points[:, 1]]
    out = np.full(len(points), -1, dtype=np.int64)
    best = np.full(len(points), HOLE_REACH * hole_radius)
    rho = np.zeros((len(points), 3))
    for k, (zk, sd, a) in enumerate(holes):
        across = np.zeros((len(points), 3))
        across[:, 1 - a] = d[:, 1 - a]
        across[:, 2] = points[:, 2] - zk
        dist = np.linalg.norm(across, axis=1)
        sel = (np.sign(d[:, a]) == sd) & (dist < best)
        out[sel], best[sel], rho[sel] = k, dist[sel], across[sel]
    return out, rho


def facet_vertices(mesh, facets: np.ndarray) -> np.ndarray:
    """Coordinates (facet, vertex, xyz) of the vertices of local facets: a facet's vertices' geometry nodes among
    those of a cell of it (the first geometry nodes of a cell are its vertices, in the cell's vertex order)."""
    tdim = mesh.topology.dim
    for d in ((tdim - 1, tdim), (tdim - 1, 0), (tdim, 0)):
        mesh.topology.create_connectivity(*d)
    f2c, f2v, c2v = (mesh.topology.connectivity(*d) for d in ((tdim - 1, tdim), (tdim - 1, 0), (tdim, 0)))
    nodes = np.zeros((len(facets), tdim), np.int64)
    for i, f in enumerate(facets):
        c = f2c.links(f)[0]
        nodes[i] = mesh.geometry.dofmap.links(c)[[list(c2v.links(c)).index(v) for v in f2v.links(f)]]
    return mesh.geometry.x[nodes]


def stent_wall_regions(mesh, facets: np.ndarray, geom, holes) -> dict:
    """{"outer": facets, "lumen": facets, "hole_<k>": facets of hole k} of the local stent-fluid facets `facets`
    (the module docstring); a facet that fits none is refused."""
    facets = np.asarray(facets, np.int32)
    p = facet_vertices(mesh, facets)                         # (facet, vertex, xyz)
    mid = p.mean(axis=1)
    normal = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
    normal /= np.linalg.norm(normal, axis=1)[:, None]
    radial = np.c_[mid[:, 0] - geom.stent_offset, mid[:, 1], np.zeros(len(mid))]
    R = np.linalg.norm(radial, axis=1)
    n_radial = np.abs(np.sum(normal * radial, axis=1)) / R
    hole, rho = _nearest_hole(mid, holes, geom.stent_offset, geom.hole_radius)
    n_hole = np.abs(np.sum(normal * rho, axis=1)) / np.where(hole >= 0, np.linalg.norm(rho, axis=1), 1.0)
    on_hole = (hole >= 0) & (n_hole > n_radial)
    is_radial = ~on_hole & (n_radial > RADIAL)
    if np.any(~on_hole & ~is_radial):
        i = np.flatnonzero(~on_hole & ~is_radial)[0]
        raise ValueError(f"stent surface: a stent-fluid facet at {mid[i].round(6).tolist()} m is neither on the outer "
                         f"surface, the lumen nor a side hole's wall")
    out = {"outer": facets[is_radial & (R > geom.probe_radius)], "lumen": facets[is_radial & (R < geom.probe_radius)]}
    return out | {f"hole_{k}": facets[on_hole & (hole == k)] for k in range(len(holes))}


class StentSurface:
    """The wall shear stress on the stent's regions (stent_wall_regions) of a problem `pb` and its time statistics,
    and the run-file summary of the holes' exchange; `holes` ((z, side, axis) each) as ureterfsi.study.probes
    .UreterProbes records them."""

    def __init__(self, pb, cfg: dict, geom, holes):
        regions = stent_wall_regions(pb.mesh, pb.scene.facet_tags.find(tags.FLUID_STENT), geom, holes)
        hole_names = [f"hole_{k}" for k in range(len(holes))]
        self.wss = WallShear(pb, regions, groups=[["outer"], ["lumen"], hole_names])
        self.names = self.wss.names
        self.history = WallShearHistory(self.wss.unit_cells.size)
        sc = cfg["stent_surface"]
        self.threshold, self.active_fraction = float(sc["low_wss_threshold"]), float(sc["active_hole_fraction"])

    def observe(self, time: float) -> dict:
        """Update the WSS at `time`; the step's area means {"stent_outer_wss", "stent_lumen_wss", "hole_wall_wss"}."""
        self.wss.update()
        self.history.add(time, self.wss.traction, self.wss.area)
        means = [self.wss.area_mean(n) for n in self.names]
        return {"stent_outer_wss": means[0], "stent_lumen_wss": means[1], "hole_wall_wss": means[2:]}

    def cell_magnitude(self) -> tuple[np.ndarray, np.ndarray]:
        """(local cells, |tau_w| there, Pa): the area-weighted mean over a cell's wall regions (field files)."""
        cells, inverse = np.unique(self.wss.unit_cells, return_inverse=True)
        mag = np.linalg.norm(self.wss.traction, axis=1)
        num, den = np.zeros(cells.size), np.zeros(cells.size)
        np.add.at(num, inverse, mag * self.wss.area)
        np.add.at(den, inverse, self.wss.area)
        return cells, num / np.where(den > 0, den, 1.0)

    def state(self) -> dict:
        return self.history.state()

    def load_state(self, state: dict) -> None:
        self.history.load_state(state)

    def summary_variables(self, comm, hole_time, gross, net) -> dict:
        """Run-file variables {name: (dims, values)}: the regions' TAWSS, OSI and low-WSS area fraction; per hole its
        gross exchange and net volume (trapezoidal over `hole_time`; `gross`, `net` (hole, time)) and its label."""
        s = self.history.region_summary(self.wss.region, len(self.names), self.threshold, comm)
        out = {}
        for key in ("tawss", "osi", "low_wss_area_fraction"):
            out[f"stent_outer_{key}"] = ((), s[key][0])
            out[f"stent_lumen_{key}"] = ((), s[key][1])
            out[f"hole_wall_{key}"] = (("hole",), s[key][2:])
        gross_volume, net_volume = (trapezoid(np.asarray(a, float), np.asarray(hole_time, float)) for a in (gross, net))
        out["hole_gross_exchange_volume"] = (("hole",), gross_volume)
        out["hole_net_volume"] = (("hole",), net_volume)
        out["hole_active"] = (("hole",), active_holes(gross_volume, self.active_fraction))
        out["low_wss_threshold"] = ((), self.threshold)
        out["active_hole_fraction"] = ((), self.active_fraction)
        return out


def trapezoid(y: np.ndarray, t: np.ndarray) -> np.ndarray:
    """int y dt along the last axis (trapezoidal rule)."""
    if t.size < 2:
        return np.zeros(y.shape[:-1])
    return np.sum(0.5 * (y[..., 1:] + y[..., :-1]) * np.diff(t), axis=-1)


def active_holes(gross_volume: np.ndarray, fraction: float) -> np.ndarray:
    """1 for a hole whose gross exchange volume exceeds `fraction` times the mean over the holes, else 0."""
    if not gross_volume.size:
        return np.zeros(0, np.int32)
    return (gross_volume > fraction * gross_volume.mean()).astype(np.int32)

