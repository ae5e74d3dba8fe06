"""Reading a gmsh .msh file (as ureterfsi.mesh.build writes it): its nodes and the simplices of its physical groups.

Imports neither dolfinx nor gmsh at import time (gmsh when a file is read), so figures use it without the
solver stack. Connectivity is in rows of `coords` (0-based): row k holds gmsh node tag k + 1.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ureterfsi.data.checked import check_msh, gmsh_error


def group_elements(dim: int, phys: int) -> np.ndarray:
    """Node-tag connectivity (n, dim+1) of the simplices of one physical group of the current gmsh model."""
    import gmsh

    conn = []
    for e in gmsh.model.getEntitiesForPhysicalGroup(dim, phys):
        types, _, nodes = gmsh.model.mesh.getElements(dim, e)
        conn += [np.asarray(n).reshape(-1, dim + 1) for n in nodes]
    return np.vstack(conn) if conn else np.zeros((0, dim + 1), dtype=np.uint64)


@dataclass(frozen=True)
class MeshFile:
    """Nodes and physical groups of a .msh file (read_msh)."""
    coords: np.ndarray      # (largest node tag, 3); row k: node tag k + 1
    groups: dict            # (dim, tag) -> (n, dim + 1) rows of coords of the group's simplices (int64)
    names: dict             # (dim, tag) -> physical name ("" if none)

    @property
    def dim(self) -> int:
        """Dimension of the cells (the highest physical group)."""
        return max(d for d, _ in self.groups)

    def cells(self) -> dict:
        """{cell tag: (n, dim + 1) rows} of the cell groups."""
        return {t: c for (d, t), c in self.groups.items() if d == self.dim}

    def elements(self, dim: int, tag: int) -> np.ndarray:
        """(n, dim + 1) rows of the simplices of group (dim, tag); none if the file has no such group."""
        return self.groups.get((dim, tag), np.zeros((0, dim + 1), dtype=np.int64))

    def nodes(self, dim: int, tag: int) -> np.ndarray:
        """(k, 3) coordinates of the distinct nodes of group (dim, tag), in node-tag order."""
        return self.coords[np.unique(self.elements(dim, tag))]


def read_msh(path) -> MeshFile:
    """The nodes, the simplices of every physical group and the group names of a .msh 4.1 file (checked by
    ureterfsi.data.checked.check_msh; BadFile if gmsh cannot read it)."""
    import gmsh

    gmsh.initialize()
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        check_msh(path)
        try:
            gmsh.merge(str(path))
        except Exception as err:  # gmsh raises a bare Exception with its last error message
            raise gmsh_error(path, err) from None
        node_tags, xyz, _ = gmsh.model.mesh.getNodes()
        coords = np.zeros((int(node_tags.max()), 3))
        coords[node_tags.astype(np.int64) - 1] = xyz.reshape(-1, 3)
        groups = {(d, t): group_elements(d, t).astype(np.int64) - 1 for d, t in gmsh.model.getPhysicalGroups()}
        names = {(d, t): gmsh.model.getPhysicalName(d, t) for d, t in groups}
    finally:
        gmsh.finalize()
    return MeshFile(coords, groups, names)
