"""Reading the run's field files (ureterfsi.study.fields: XDMF 3 + HDF5) without dolfinx, for figures and checks.

HDF5 is read through netCDF4 (HDF5 files are netCDF-4 readable), so no second HDF5 binding is loaded. The figures
drawn from them: ureterfsi.plotting.fields.
"""
from __future__ import annotations

import xml.etree.ElementTree as ET
from dataclasses import dataclass
from pathlib import Path

import netCDF4
import numpy as np
from scipy.spatial import cKDTree

from ureterfsi.mesh import tags
from ureterfsi.data.checked import BadFile, Contract, read_json

# the index of a run's field files (ureterfsi.study.fields) as the readers here use it
FIELDS_INDEX = Contract("field-files index", attrs=("parts", "units"), versioned=False)


def _read(directory: Path, item: str) -> np.ndarray:
    """Array of an XDMF HDF DataItem text 'file.h5:/group/.../name'."""
    fname, path = item.strip().split(":", 1)
    *groups, name = path.strip("/").split("/")
    h5 = directory / fname
    if not h5.is_file():
        raise BadFile(h5, "no such field file (listed in the XDMF index)")
    try:
        with netCDF4.Dataset(h5) as ds:
            node = ds
            for g in groups:
                node = node.groups[g]
            return np.asarray(node.variables[name][:])
    except KeyError:
        raise BadFile(h5, f"field file without the data set {path} its XDMF index lists") from None
    except Exception as err:  # netCDF4/HDF5: OSError, RuntimeError on a truncated or foreign file
        raise BadFile(h5, f"truncated or corrupt field file ({type(err).__name__}: {err})") from None


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
        raise BadFile(index, f"no field file of part {part!r}")
    try:
        root = ET.parse(index).getroot()
    except ET.ParseError as err:
        raise BadFile(index, f"not valid XDMF (XML: {err}); truncated?") from None
    grids = [g for g in root.iter("Grid") if g.get("GridType") == "Uniform"]
    if not grids:
        raise BadFile(index, "XDMF index without snapshots (no Uniform grid)")
    topo = _read(directory, grids[0].find("Topology/DataItem").text)
    geom = _read(directory, grids[0].find("Geometry/DataItem").text)
    times = np.array([float(g.find("Time").get("Value")) for g in grids])
    items = [{a.get("Name"): a.find("DataItem").text for a in g.findall("Attribute")} for g in grids]
    units = read_json(directory / "fields.json", FIELDS_INDEX)["units"]
    return FieldSet(directory, geom, topo.astype(np.int64), times, items, units)


def _inv3(A: np.ndarray) -> np.ndarray:
    """Inverses of a stack of 3x3 matrices (n, 3, 3) with rows r0, r1, r2: A^-1 = [r1 x r2 | r2 x r0 | r0 x r1]
    / det A, vectorised (numpy.linalg.inv is far slower on many small matrices, docs/fields.md)."""
    r0, r1, r2 = A[:, 0], A[:, 1], A[:, 2]
    adj = np.stack([np.cross(r1, r2), np.cross(r2, r0), np.cross(r0, r1)], axis=2)
    det = np.einsum("ni,ni->n", r0, adj[:, :, 0])
    return adj / det[:, None, None]


def urine_fields(directory) -> FieldSet:
    """The part of a run's field output that holds the urine: `domain` (fully coupled) or `urine` (one-way)."""
    parts = read_json(Path(directory) / "fields.json", FIELDS_INDEX)["parts"]
    name = next((p for p in ("domain", "urine") if p in parts), None)
    if name is None:
        raise KeyError(f"{directory}/fields.json: no part with the urine (domain or urine), has {sorted(parts)}")
    return read_fields(directory, name)


def urine_cells(fs: FieldSet) -> np.ndarray:
    """Boolean mask of the part's urine cells: subdomain == tags.FLUID where the part has its cell tags (the
    whole mesh of a fully coupled run), every cell otherwise (the one-way rung's fluid submesh)."""
    if "subdomain" not in fs.items[0]:
        return np.ones(len(fs.cells), dtype=bool)
    return fs.values("subdomain", float(fs.times[0]))[:, 0] == tags.FLUID


def sample(fs: FieldSet, quantity: str, time: float, points: np.ndarray, current: bool = False,
           cells: np.ndarray | None = None) -> np.ndarray:
    """Piecewise-linear values of a nodal quantity at `points` (m; NaN outside the part's cells, or outside
    the cells of the boolean mask `cells`). current: the points are in the current configuration x = X + u
    (the part's `displacement` at that time)."""
    X = fs.points + (fs.values("displacement", time) if current else 0.0)
    vals = fs.values(quantity, time)
    conn = fs.cells if cells is None else fs.cells[cells]
    tet = X[conn]                                       # (cells, 4, 3)
    T = np.transpose(tet[:, 1:] - tet[:, :1], (0, 2, 1))  # columns x1-x0, x2-x0, x3-x0
    Tinv = _inv3(T)
    tree = cKDTree(tet.mean(axis=1))
    out = np.full((len(points), vals.shape[1]), np.nan)
    todo, k = np.arange(len(points)), 0
    for kk in (24, 96):                     # nearest cell centroids first, then more for the points left
        kk = min(kk, len(conn))
        if not todo.size or kk <= k:
            break
        cand = tree.query(points[todo], k=kk)[1].reshape(todo.size, -1)[:, k:]
        for j in range(cand.shape[1]):
            c = cand[:, j]
            lam = np.einsum("nij,nj->ni", Tinv[c], points[todo] - tet[c, 0])
            bary = np.c_[1.0 - lam.sum(axis=1), lam]
            inside = (bary > -1e-9).all(axis=1) & np.isnan(out[todo, 0])
            out[todo[inside]] = np.einsum("ni,nic->nc", bary[inside], vals[conn[c[inside]]])
        todo, k = todo[np.isnan(out[todo, 0])], kk
    return out


@dataclass
class Section:
    """Values sampled on a grid of the plane x = 0: y, z (m, 1-D axes) and per time (s) an array (y, z, ...)."""
    y: np.ndarray
    z: np.ndarray
    times: list
    values: list


def hole_flow_section(fs: FieldSet, times, hole_z: float, geom, half_width: float = 2.0e-3, y=None,
                      z=None) -> Section:
    """Urine velocity (m s-1) on the plane x = 0 in the current configuration at each of `times`, NaN off the
    urine; on the axes y, z (m), by default 90 points over 0 <= y <= 1.05 R_i and 120 over |z - hole_z| <=
    half_width (within the segment) around the side hole at z = hole_z."""
    y = np.linspace(0.0, geom.ureter_inner_radius * 1.05, 90) if y is None else np.asarray(y, float)
    z = (np.linspace(max(hole_z - half_width, 0.0), min(hole_z + half_width, geom.length), 120) if z is None
         else np.asarray(z, float))
    ny, nz = y.size, z.size
    Y, Z = np.meshgrid(y, z, indexing="ij")
    pts = np.c_[np.zeros(Y.size), Y.ravel(), Z.ravel()]
    urine = urine_cells(fs)
    vals = [sample(fs, "velocity", t, pts, current=True, cells=urine).reshape(ny, nz, -1) for t in times]
    return Section(y, z, [float(t) for t in times], vals)


def pressure_lines(fs: FieldSet, times, geom, n: int = 300) -> dict:
    """Urine pressure (Pa) along z at each of `times` on two lines of the plane y = 0 (reference
    configuration, which the ALE mesh keeps on the moving wall): the ureter inner wall r = R_i and the stent
    lumen r = r_i / 2. Returns {label: (z, array (time, z))}."""
    z = np.linspace(0.0, geom.length, n)
    radii = {"ureter inner wall": geom.ureter_inner_radius * (1 - 1e-6),
             "stent lumen (r = r_i / 2)": 0.5 * geom.stent_inner_radius}
    urine = urine_cells(fs)
    return {label: (z, np.array([sample(fs, "pressure", t, np.c_[np.full_like(z, r), np.zeros_like(z), z],
                                        cells=urine)[:, 0] for t in times]))
            for label, r in radii.items()}


@dataclass
class StentWallShear:
    """The stent's wall shear stress (Pa) from the field files at each of `times`: per urine cell beside the stent
    within half_width of the hole, its centroid's angle around the stent axis (rad), z (m) and radius (m)."""
    theta: np.ndarray
    z: np.ndarray
    radius: np.ndarray
    times: list
    values: list


def stent_wall_shear(fs: FieldSet, times, hole_z: float, geom, half_width: float = 2.0e-3) -> StentWallShear:
    """The `wall_shear_stress` cell field of the urine cells beside the stent (finite values) within |z - hole_z| <=
    half_width, reference centroids: angle from the x axis around the stent axis (x = stent_offset, y = 0)."""
    centroid = fs.points[fs.cells].mean(axis=1)
    first = fs.values("wall_shear_stress", float(times[0]))[:, 0]
    keep = np.isfinite(first) & (np.abs(centroid[:, 2] - hole_z) <= half_width)
    c = centroid[keep]
    return StentWallShear(np.arctan2(c[:, 1], c[:, 0] - geom.stent_offset), c[:, 2],
                          np.hypot(c[:, 0] - geom.stent_offset, c[:, 1]), [float(t) for t in times],
                          [fs.values("wall_shear_stress", float(t))[keep, 0] for t in times])
