"""What a built mesh has: measure of its simplices, gmsh's cell quality (minSICN), the side-hole channels found in it
and the resolution across a hole (the mesh sidecar's statistics)."""
from __future__ import annotations

import math

import gmsh
import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components


def simplex_measure(conn: np.ndarray, coords: np.ndarray) -> float:
    """Total volume (3D) or area (2D) of simplices."""
    p = coords[conn - 1][:, :, :conn.shape[1] - 1]
    d = p[:, 1:] - p[:, :1]
    return float(np.abs(np.linalg.det(d)).sum() / math.factorial(d.shape[1]))


def cell_quality(dim: int) -> dict:
    """gmsh minSICN (plugin AnalyseMeshQuality, ICN measure) of all cells: min, 1st percentile, median."""
    for opt, val in (("JacobianDeterminant", 0), ("IGEMeasure", 0), ("ICNMeasure", 1), ("CreateView", 1),
                     ("DimensionOfElements", dim)):
        gmsh.plugin.setNumber("AnalyseMeshQuality", opt, val)
    gmsh.plugin.run("AnalyseMeshQuality")
    view = gmsh.view.getTags()[-1]
    _, _, data, _, _ = gmsh.view.getModelData(view, 0)
    gmsh.view.remove(view)
    q = np.concatenate(data)
    return {"min": float(q.min()), "p01": float(np.percentile(q, 1)), "median": float(np.median(q))}


def _hole_wall_triangles(coords: np.ndarray, tris: np.ndarray, stent_offset: float = 0.0) -> np.ndarray:
    """FLUID_STENT triangles on hole walls: normal across the radial direction from the stent axis (x_s, 0)
    (hole axis radial), unlike the stent's lumen and outer walls."""
    p = coords[tris - 1]
    n = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
    n /= np.linalg.norm(n, axis=1)[:, None]
    c = p.mean(axis=1) - np.array([stent_offset, 0.0, 0.0])
    er = c[:, :2] / np.linalg.norm(c[:, :2], axis=1)[:, None]
    return tris[np.abs((n[:, :2] * er).sum(axis=1)) < 0.7]


def hole_resolution(coords: np.ndarray, tris: np.ndarray, diameter: float, stent_offset: float = 0.0) -> dict:
    """Mean edge length of the hole-wall triangles and the elements across a hole it gives (diameter / it):
    the resolution the mesh has, whatever the size fields asked for."""
    wall = _hole_wall_triangles(coords, tris, stent_offset)
    if not len(wall):
        return {}
    p = coords[wall - 1]
    edges = np.linalg.norm(p - np.roll(p, 1, axis=1), axis=2)
    h = float(edges.mean())
    return {"hole_wall_edge_mean": h, "hole_elements_across": diameter / h}


def hole_channels(coords: np.ndarray, tris: np.ndarray, stent_offset: float = 0.0) -> list:
    """Hole channels found in a mesh: connected groups of FLUID_STENT triangles on hole walls
    (_hole_wall_triangles). Returns per channel {"axis", "sign", "z", "across"}: axis "x" or "y" the one its wall
    lies along (from the stent axis (x_s, 0)), sign the side on it, z its centre and across the [min, max] of its
    wall's other in-plane coordinate (-a to a for a whole hole, 0 to a for one cut in half by a mirror plane);
    sorted by z, axis, sign.
    """
    wall = _hole_wall_triangles(coords, tris, stent_offset)
    if not len(wall):
        return []
    nodes, local = np.unique(wall, return_inverse=True)
    local = local.reshape(-1, 3)
    rows = np.repeat(np.arange(len(wall)), 3)  # triangle-node incidence; components via bipartite graph
    graph = coo_matrix((np.ones(rows.size), (rows, len(wall) + local.ravel())),
                       shape=(len(wall) + nodes.size,) * 2)
    _, label = connected_components(graph, directed=False)
    shift = np.array([stent_offset, 0.0, 0.0])
    cw = coords[wall - 1].mean(axis=1) - shift
    out = []
    for k in np.unique(label[:len(wall)]):
        c = cw[label[:len(wall)] == k].mean(axis=0)
        axis = int(abs(c[1]) > abs(c[0]))
        across = coords[wall[label[:len(wall)] == k].ravel() - 1, 1 - axis] - shift[1 - axis]
        out.append({"axis": "xy"[axis], "sign": int(np.sign(c[axis])), "z": float(c[2]),
                    "across": [float(across.min()), float(across.max())]})
    return sorted(out, key=lambda t: (round(t["z"], 6), t["axis"], t["sign"]))
