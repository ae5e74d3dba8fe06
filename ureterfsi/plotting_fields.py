"""Reading the run's field files (ureterfsi.fields: XDMF 3 + HDF5) without dolfinx, for figures and checks.

HDF5 is read through netCDF4 (HDF5 files are netCDF-4 readable), so no second HDF5 binding is loaded.
"""
from __future__ import annotations

import json
import xml.etree.ElementTree as ET
from dataclasses import dataclass
from pathlib import Path

import netCDF4
import numpy as np


def _read(directory: Path, item: str) -> np.ndarray:
    """Array of an XDMF HDF DataItem text 'file.h5:/group/.../name'."""
    fname, path = item.strip().split(":", 1)
    *groups, name = path.strip("/").split("/")
    with netCDF4.Dataset(directory / fname) as ds:
        node = ds
        for g in groups:
            node = node.groups[g]
        return np.asarray(node.variables[name][:])


@dataclass
class FieldSet:
    """One part of a run's field output: reference vertex coordinates (m), cells, snapshot times (s) and
    the data item of each (time, quantity)."""
    directory: Path
    points: np.ndarray
    cells: np.ndarray
    times: np.ndarray
    items: list
    units: dict

    def values(self, quantity: str, time: float) -> np.ndarray:
        """Values (vertices or cells, components) of a quantity at the snapshot time nearest to `time`, which
        must be a snapshot time within 1e-9 s."""
        k = int(np.argmin(np.abs(self.times - time)))
        if abs(self.times[k] - time) > 1e-9:
            raise KeyError(f"{self.directory}: no snapshot at t = {time:g} s (times {self.times.tolist()})")
        if quantity not in self.items[k]:
            raise KeyError(f"{self.directory}: no quantity {quantity!r} (has {sorted(self.items[k])})")
        return _read(self.directory, self.items[k][quantity])


def read_fields(directory, part: str) -> FieldSet:
    """The part's FieldSet from <directory>/<part>.xdmf and fields.json."""
    directory = Path(directory)
    index = directory / f"{part}.xdmf"
    if not index.exists():
        raise FileNotFoundError(f"{index}: no field file of part {part!r}")
    root = ET.parse(index).getroot()
    grids = [g for g in root.iter("Grid") if g.get("GridType") == "Uniform"]
    topo = _read(directory, grids[0].find("Topology/DataItem").text)
    geom = _read(directory, grids[0].find("Geometry/DataItem").text)
    times = np.array([float(g.find("Time").get("Value")) for g in grids])
    items = [{a.get("Name"): a.find("DataItem").text for a in g.findall("Attribute")} for g in grids]
    units = json.loads((directory / "fields.json").read_text())["units"]
    return FieldSet(directory, geom, topo.astype(np.int64), times, items, units)


def sample(fs: FieldSet, quantity: str, time: float, points: np.ndarray, current: bool = False) -> np.ndarray:
    """Piecewise-linear values of a nodal quantity at `points` (m; NaN outside the part's cells). current:
    the points are in the current configuration x = X + u (the part's `displacement` at that time)."""
    from scipy.spatial import cKDTree

    X = fs.points + (fs.values("displacement", time) if current else 0.0)
    vals = fs.values(quantity, time)
    tet = X[fs.cells]                                   # (cells, 4, 3)
    T = np.transpose(tet[:, 1:] - tet[:, :1], (0, 2, 1))  # columns x1-x0, x2-x0, x3-x0
    Tinv = np.linalg.inv(T)
    tree = cKDTree(tet.mean(axis=1))
    out = np.full((len(points), vals.shape[1]), np.nan)
    _, cand = tree.query(points, k=min(24, len(fs.cells)))
    for j in range(cand.shape[1]):
        todo = np.isnan(out[:, 0])
        if not todo.any():
            break
        c = cand[todo, j]
        lam = np.einsum("nij,nj->ni", Tinv[c], points[todo] - tet[c, 0])
        bary = np.c_[1.0 - lam.sum(axis=1), lam]
        inside = (bary > -1e-9).all(axis=1)
        idx = np.flatnonzero(todo)[inside]
        out[idx] = np.einsum("ni,nic->nc", bary[inside], vals[fs.cells[c[inside]]])
    return out


def fig_hole_flow(fs: FieldSet, times, hole_z: float, geom, title: str, half_width: float = 2.0e-3):
    """Urine velocity in the plane x = 0 around the side hole at z = hole_z, current configuration, at each
    of `times`: speed (colour) and streamlines of the in-plane velocity (v_y, v_z); stent wall and hole outlined."""
    import matplotlib.pyplot as plt
    from matplotlib.patches import Rectangle

    ny, nz = 90, 120
    y = np.linspace(0.0, geom.ureter_inner_radius * 1.05, ny)
    z = np.linspace(hole_z - half_width, hole_z + half_width, nz)
    Y, Z = np.meshgrid(y, z, indexing="ij")
    pts = np.c_[np.zeros(Y.size), Y.ravel(), Z.ravel()]
    fig, axes = plt.subplots(1, len(times), figsize=(3.2 * len(times) + 1.0, 4.2), sharey=True, constrained_layout=True)
    axes = np.atleast_1d(axes)
    fields = [sample(fs, "velocity", t, pts, current=True).reshape(ny, nz, -1) for t in times]
    vmax = max(float(np.nanmax(np.linalg.norm(v, axis=2))) for v in fields) * 1e3
    for ax, t, v in zip(axes, times, fields):
        speed = np.linalg.norm(v, axis=2) * 1e3
        im = ax.pcolormesh(Z * 1e3, Y * 1e3, speed, shading="auto", cmap="viridis", vmin=0.0, vmax=vmax)
        vy, vz = np.nan_to_num(v[..., 1]), np.nan_to_num(v[..., 2])
        ax.streamplot(z * 1e3, y * 1e3, vz, vy, color="w", density=1.1, linewidth=0.6, arrowsize=0.7)
        ri, ro, rh = geom.stent_inner_radius * 1e3, geom.stent_outer_radius * 1e3, geom.hole_radius * 1e3
        zl, zh = (hole_z - half_width) * 1e3, (hole_z + half_width) * 1e3
        for a, b in ((zl, hole_z * 1e3 - rh), (hole_z * 1e3 + rh, zh)):
            ax.add_patch(Rectangle((a, ri), b - a, ro - ri, facecolor="0.6", edgecolor="k", lw=0.8))
        ax.set_title(f"t = {t:g} s")
        ax.set_xlabel("z (mm)")
        ax.set_xlim(zl, zh)
    axes[0].set_ylabel("y (mm), plane x = 0")
    fig.colorbar(im, ax=axes, label="urine speed |v| (mm s$^{-1}$)")
    fig.suptitle(title)
    return fig


def fig_pressure_along(fs: FieldSet, times, geom, p_ref: float, title: str):
    """Urine pressure minus the reference pressure along the segment at each of `times`: on the ureter inner
    wall (r = R_i, plane y = 0) and in the stent lumen (r = r_i / 2) or on the axis without a stent."""
    import matplotlib.pyplot as plt

    z = np.linspace(0.0, geom.length, 300)
    lines = {"ureter inner wall": geom.ureter_inner_radius * (1 - 1e-6),
             "lumen (stent or axis)": 0.5 * geom.stent_inner_radius}
    fig, axes = plt.subplots(len(lines), 1, figsize=(7.0, 5.5), sharex=True, constrained_layout=True)
    for ax, (label, r) in zip(axes, lines.items()):
        pts = np.c_[np.full_like(z, r), np.zeros_like(z), z]
        for t in times:
            p = sample(fs, "pressure", t, pts)[:, 0]
            ax.plot(z * 1e3, p - p_ref, label=f"t = {t:g} s")
        ax.set_ylabel(f"p - p_ref (Pa)\n{label}")
        ax.grid(alpha=0.3)
    axes[0].legend(fontsize=8)
    axes[-1].set_xlabel("z (mm), inlet 0 to outlet")
    fig.suptitle(title)
    return fig
