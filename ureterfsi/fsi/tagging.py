"""Tag cells and boundary facets of a mesh by geometric predicates (for scenes built on dolfinx meshes)."""
from __future__ import annotations

import numpy as np
from dolfinx import mesh as dmesh


def tag_cells(mesh, markers: dict):
    """MeshTags of cells: markers {tag: predicate(x) -> bool array} evaluated at cell midpoints;
    later entries win where predicates overlap. Untagged cells get no tag."""
    tdim = mesh.topology.dim
    n = mesh.topology.index_map(tdim).size_local + mesh.topology.index_map(tdim).num_ghosts
    cells = np.arange(n, dtype=np.int32)
    mid = dmesh.compute_midpoints(mesh, tdim, cells).T
    values = np.zeros(n, dtype=np.int32)
    for tag, pred in markers.items():
        values[pred(mid)] = tag
    keep = values > 0
    return dmesh.meshtags(mesh, tdim, cells[keep], values[keep])


def tag_facets(mesh, markers: dict, cell_tags=None, interfaces: dict | None = None):
    """MeshTags of facets: exterior facets by predicates {tag: predicate(x)} at facet midpoints, and
    interior facets between two cell tags by `interfaces` {tag: (cell_tag_a, cell_tag_b)}."""
    tdim = mesh.topology.dim
    fdim = tdim - 1
    mesh.topology.create_connectivity(fdim, tdim)
    indices, values = [], []
    exterior = dmesh.exterior_facet_indices(mesh.topology)
    if exterior.size:
        mid = dmesh.compute_midpoints(mesh, fdim, exterior).T
        vals = np.zeros(exterior.size, dtype=np.int32)
        for tag, pred in markers.items():
            vals[pred(mid)] = tag
        indices.append(exterior[vals > 0])
        values.append(vals[vals > 0])
    if interfaces:
        f2c = mesh.topology.connectivity(fdim, tdim)
        ctag = np.zeros(mesh.topology.index_map(tdim).size_local + mesh.topology.index_map(tdim).num_ghosts,
                        dtype=np.int32)
        ctag[cell_tags.indices] = cell_tags.values
        nf = mesh.topology.index_map(fdim).size_local + mesh.topology.index_map(fdim).num_ghosts
        for tag, (a, b) in interfaces.items():
            found = [f for f in range(nf) if len(f2c.links(f)) == 2
                     and {ctag[c] for c in f2c.links(f)} == {a, b}]
            indices.append(np.array(found, dtype=np.int32))
            values.append(np.full(len(found), tag, dtype=np.int32))
    idx = np.concatenate(indices) if indices else np.zeros(0, np.int32)
    val = np.concatenate(values) if values else np.zeros(0, np.int32)
    order = np.argsort(idx)
    return dmesh.meshtags(mesh, fdim, idx[order], val[order])
