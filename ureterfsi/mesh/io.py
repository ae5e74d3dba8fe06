"""gmsh .msh files (as ureterfsi.mesh.build writes them): reading nodes and physical groups (read_msh), the one
writer (write_msh), loading into dolfinx (load_mesh), mirroring a symmetric mesh into the full one (mirror_mesh).

Imports neither dolfinx nor gmsh at import time (gmsh when a file is read or written), so figures use it without the
solver stack. Connectivity is in rows of `coords` (0-based): row k holds gmsh node tag k + 1.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ureterfsi.data.checked import BadFile, check_msh, gmsh_error
from ureterfsi.data.provenance import atomic_path
from ureterfsi.mesh import tags


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


def write_msh(path) -> None:
    """Write the current gmsh model's physical groups to `path` (ASCII .msh 4.1), atomically: the one .msh writer."""
    import gmsh

    gmsh.option.setNumber("Mesh.MshFileVersion", 4.1)
    gmsh.option.setNumber("Mesh.SaveAll", 0)
    gmsh.option.setNumber("Mesh.Binary", 0)
    with atomic_path(path) as tmp:
        part = tmp.with_name(tmp.name[:-len(".part")])  # gmsh picks the format from the extension
        try:
            gmsh.write(str(part))
            part.replace(tmp)
        finally:
            part.unlink(missing_ok=True)


def load_mesh(msh_path, comm, expect: tuple | None = None):
    """(mesh, cell_tags, facet_tags) of a mesh written by build_mesh (gdim 2 for the r-z section). With `expect`
    = (symmetry, stent, what): the mesh must be of that symmetry's dimension (2 for axisymmetric, else 3) and
    have stent cells exactly if `stent`, else BadFile naming `what` (the run it was handed to).

    dolfinx 0.5.2's gmshio.read_from_msh is broken (finalizes gmsh before building the mesh), so the
    file is merged here on rank 0 and handed to gmshio.model_to_mesh on every rank.
    """
    import gmsh
    from dolfinx.io import gmshio   # lazy: building a mesh (rule mesh) needs no dolfinx

    gdim, bad = None, None
    if comm.rank == 0:
        gmsh.initialize()
        gmsh.option.setNumber("General.Terminal", 0)
        try:
            check_msh(msh_path)
            try:
                gmsh.merge(str(msh_path))
            except Exception as err:  # gmsh raises a bare Exception with its last error message
                raise gmsh_error(msh_path, err) from None
            groups = gmsh.model.getPhysicalGroups()
            cell_dim = max((d for d, _ in groups), default=0)
            cell_tags = {t for d, t in groups if d == cell_dim}
            if cell_dim not in (2, 3) or not cell_tags <= set(tags.CELL_NAMES) or tags.FLUID not in cell_tags:
                raise BadFile(msh_path, f"not a ureterfsi mesh (physical groups {sorted(groups)}; expected cells "
                                        f"tagged {sorted(tags.CELL_NAMES)} with fluid {tags.FLUID})")
            if expect is not None:
                symmetry, stent, what = expect
                want_dim, has_stent = 2 if symmetry == "axisymmetric" else 3, tags.STENT in cell_tags
                if cell_dim != want_dim or has_stent != bool(stent):
                    def kind(d, s):
                        return f"a {d}D mesh {'with' if s else 'without'} stent cells"
                    raise BadFile(msh_path, f"{kind(cell_dim, has_stent)}, but {what} needs "
                                            f"{kind(want_dim, bool(stent))} (the mesh of another model or symmetry?); "
                                            f"re-run the rule that makes it")
            gdim = cell_dim
        except BadFile as err:
            bad = err
            gmsh.finalize()
    bad = comm.bcast(bad, root=0)
    if bad is not None:
        raise bad
    gdim = comm.bcast(gdim, root=0)
    try:
        return gmshio.model_to_mesh(gmsh.model, comm, 0, gdim=gdim)
    finally:
        if comm.rank == 0:
            gmsh.finalize()


def mirror_mesh(src, dst, symmetry: str) -> dict:
    """Reflect a half or quarter mesh into the full one (x = 0 mirror, then y = 0 for a quarter; y = 0 for the
    half model of an offset stent, the plane its symmetry_y facets name) and write
    it to `dst` (.msh 4.1, the same physical groups, the mirror-plane facet groups dropped: they become
    interior). The full mesh is the symmetric mesh's discretisation repeated, node for node, so a full-model
    solve on it differs from the symmetric solve only by what the symmetry conditions change: nothing, in
    exact arithmetic, for a symmetric problem. Returns {"cells", "nodes"}."""
    import gmsh

    planes = {"half": [(0, tags.SYMMETRY_X)], "quarter": [(0, tags.SYMMETRY_X), (1, tags.SYMMETRY_Y)]}
    if symmetry not in planes:
        raise ValueError(f"mirror_mesh: symmetry must be 'half' or 'quarter', got {symmetry!r}")
    src_mesh = read_msh(src)
    coords, names, dim = src_mesh.coords, src_mesh.names, src_mesh.dim
    groups = {k: c + 1 for k, c in src_mesh.groups.items()}     # node tags
    if dim != 3:
        raise ValueError(f"mirror_mesh: {src} is not a 3D mesh")
    if symmetry == "half" and (dim - 1, tags.SYMMETRY_X) not in groups:
        planes["half"] = [(1, tags.SYMMETRY_Y)]
    tol = 1e-9 * np.abs(coords).max()
    for axis, plane_tag in planes[symmetry]:
        groups.pop((dim - 1, plane_tag), None)
        n = coords.shape[0]
        on_plane = np.abs(coords[:, axis]) <= tol
        image = np.where(on_plane, np.arange(n), n + np.arange(n))   # 0-based node -> its mirror image
        mirrored = coords.copy()
        mirrored[:, axis] *= -1.0
        coords = np.vstack([coords, mirrored])
        for key, conn in groups.items():
            im = image[conn - 1] + 1
            if key[0] == dim:
                im[:, [0, 1]] = im[:, [1, 0]]         # a reflection flips the orientation: swap back
            groups[key] = np.vstack([conn, im])
    # compact node numbering 1..N (gmshio needs contiguous node tags)
    used = np.unique(np.concatenate([c.ravel() for c in groups.values()]))
    number = np.zeros(coords.shape[0] + 1, dtype=np.int64)
    number[used] = np.arange(1, used.size + 1)
    coords, groups = coords[used - 1], {k: number[c] for k, c in groups.items()}
    used = np.arange(1, used.size + 1)
    gmsh.initialize()
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.model.add("mirrored")
        first = True
        element_tag = 1
        for (d, t), conn in sorted(groups.items(), key=lambda kv: -kv[0][0]):
            entity = gmsh.model.addDiscreteEntity(d)
            if first:      # every node lives on the first volume entity
                gmsh.model.mesh.addNodes(d, entity, used, coords[used - 1].ravel())
                first = False
            etype = gmsh.model.mesh.getElementType("tetrahedron" if d == 3 else "triangle", 1)
            gmsh.model.mesh.addElementsByType(entity, etype, np.arange(element_tag, element_tag + len(conn)),
                                              conn.ravel())
            element_tag += len(conn)
            gmsh.model.addPhysicalGroup(d, [entity], t)
            if names[(d, t)]:
                gmsh.model.setPhysicalName(d, t, names[(d, t)])
        write_msh(dst)
    finally:
        gmsh.finalize()
    return {"cells": int(sum(len(c) for (d, _), c in groups.items() if d == dim)), "nodes": int(used.size)}
