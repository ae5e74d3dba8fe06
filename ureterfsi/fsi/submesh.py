"""Sub-domain meshes: the cells of some tagged regions as a mesh of their own, with their tags.

Reduced models (e.g. the fluid alone on its part of the conforming FSI mesh, or the stent alone)
solve on a sub-domain. `extract` builds the submesh (dolfinx.mesh.create_submesh), carries the cell
tags over and re-tags its facets: a facet keeps the tag of its parent facet, so interfaces tagged in
the parent (fluid-ureter, fluid-stent) become tagged boundaries of the submesh.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from dolfinx import mesh as dmesh


@dataclass
class SubDomain:
    mesh: object
    cell_tags: object
    facet_tags: object
    parent_cells: np.ndarray      # submesh cell -> parent cell
    parent_vertices: np.ndarray   # submesh vertex -> parent vertex


def _facet_keys(msh, facets) -> np.ndarray:
    """Sorted vertex indices of each facet (one row per facet)."""
    tdim = msh.topology.dim
    msh.topology.create_connectivity(tdim - 1, 0)
    f2v = msh.topology.connectivity(tdim - 1, 0)
    nv = len(f2v.links(0)) if len(facets) else tdim
    return np.sort(np.array([f2v.links(f) for f in facets], dtype=np.int64).reshape(-1, nv), axis=1)


def extract(msh, cell_tags, facet_tags, region_tags) -> SubDomain:
    """Submesh of the cells tagged with any of `region_tags`, with cell and facet tags (serial)."""
    if msh.comm.size > 1:
        raise NotImplementedError("sub-domain extraction runs on one process (reduced models are serial)")
    tdim = msh.topology.dim
    cells = np.unique(np.concatenate([cell_tags.find(t) for t in region_tags])).astype(np.int32)
    sub, cell_map, vertex_map, _ = dmesh.create_submesh(msh, tdim, cells)
    cell_map, vertex_map = np.asarray(cell_map, np.int32), np.asarray(vertex_map, np.int64)

    parent_tag = np.full(msh.topology.index_map(tdim).size_local, -1, np.int32)
    parent_tag[cell_tags.indices] = cell_tags.values
    sub_cells = np.arange(len(cell_map), dtype=np.int32)
    sub_ct = dmesh.meshtags(sub, tdim, sub_cells, parent_tag[cell_map])

    # parent facet (as parent-vertex key) -> tag; submesh facets keyed by their parent vertices
    sub.topology.create_entities(tdim - 1)
    nsub = sub.topology.index_map(tdim - 1).size_local
    sub_keys = np.sort(vertex_map[_facet_keys(sub, np.arange(nsub, dtype=np.int32))], axis=1)
    lookup = {tuple(k): i for i, k in enumerate(sub_keys)}
    parent_keys = _facet_keys(msh, facet_tags.indices)
    hits = [(lookup.get(tuple(k)), v) for k, v in zip(parent_keys, facet_tags.values)]
    hits = sorted((i, v) for i, v in hits if i is not None)
    idx = np.array([i for i, _ in hits], dtype=np.int32)
    val = np.array([v for _, v in hits], dtype=np.int32)
    sub_ft = dmesh.meshtags(sub, tdim - 1, idx, val)
    return SubDomain(sub, sub_ct, sub_ft, cell_map, vertex_map)


def untagged_boundary_facets(sub: SubDomain) -> np.ndarray:
    """Exterior facets of the submesh without a tag (should be none for a well-tagged parent)."""
    tdim = sub.mesh.topology.dim
    sub.mesh.topology.create_connectivity(tdim - 1, tdim)
    ext = dmesh.exterior_facet_indices(sub.mesh.topology)
    return np.setdiff1d(ext, sub.facet_tags.indices)
