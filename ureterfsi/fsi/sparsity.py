"""Sparsity of the engine's Jacobian matrices: the (cell region, field pair) couplings its forms have.

A mixed element's pattern couples every dof of a cell with every other (64 x 64 on a P2-P2-P1 tetrahedron). The
Newton system's forms couple fewer field pairs, per cell region (rows <- columns):

- coupled system (`coupled_matrix`): fluid cells v, p <- v, p, u (ALE Navier-Stokes, open boundaries) and
  u <- u (mesh motion); solid cells v <- v, u (+ pi) (inertia, stress), u <- u, v (kinematics), pi <- u, pi
  (Mooney-Rivlin); every diagonal (pinned and Dirichlet rows);
- fluid-alone system with segregated mesh motion (`flow_matrix`): v, p <- v, p on every cell and the diagonal
  of the mirrored mesh-displacement rows (the flow rows see the mesh displacement as a coefficient).

The same matrix with fewer stored entries: a cheaper assembly and factorisation (docs/performance.md).
"""
from __future__ import annotations

import numpy as np
from dolfinx import cpp as _cpp
from dolfinx import fem
from petsc4py import PETSc


def num_cells(mesh) -> int:
    """Local cells, ghosts included."""
    cmap = mesh.topology.index_map(mesh.topology.dim)
    return cmap.size_local + cmap.num_ghosts


def cell_dofs(W: fem.FunctionSpace, field_names: list, field: str) -> np.ndarray:
    """(cells, dofs per cell) local dofs of one field of the mixed space W (fields `field_names`) in W's numbering."""
    return W.sub(field_names.index(field)).dofmap.list.array.reshape(num_cells(W.mesh), -1)


def pattern_matrix(W: fem.FunctionSpace, field_names: list, blocks, diagonal) -> PETSc.Mat:
    """PETSc matrix on W whose nonzeros are, for each (cells, row fields, column fields) of `blocks`, every row
    dof of a cell coupled with every column dof of that cell, plus the local rows `diagonal`; the structure
    fixed with zeros. Assembly inserts the whole mixed element's cell matrices: entries outside the pattern must
    be exact zeros, which PETSc skips before searching their row (MAT_IGNORE_ZERO_ENTRIES) - except on the
    diagonal: a cell's diagonal outside the pattern fails the insertion of that cell matrix (silently in a
    release build of dolfinx), hence every diagonal a cell reaches is in the pattern."""
    comm = W.mesh.comm
    imap, bs = W.dofmap.index_map, W.dofmap.index_map_bs
    pattern = _cpp.la.SparsityPattern(comm, [imap, imap], [bs, bs])
    for cells, rows, cols in blocks:
        if not rows or cells.size == 0:
            continue
        r = np.hstack([cell_dofs(W, field_names, f) for f in rows])[cells].astype(np.int32)
        c = np.hstack([cell_dofs(W, field_names, f) for f in cols])[cells].astype(np.int32)
        for ri, ci in zip(r, c):
            pattern.insert(ri, ci)
    pattern.insert_diagonal(np.asarray(diagonal, dtype=np.int32))
    pattern.assemble()
    A = _cpp.la.petsc.create_matrix(comm, pattern)
    # fix the structure with zeros: the graph's owned rows, its columns in the pattern's own numbering
    graph, owned = pattern.graph, imap.size_local * bs
    offsets = graph.offsets[:owned + 1]
    cols = pattern.column_index_map().local_to_global(graph.array[:offsets[-1]])
    A.setValuesCSR(offsets.astype(PETSc.IntType), cols.astype(PETSc.IntType),
                   np.zeros(cols.size, dtype=PETSc.ScalarType))
    A.assemble()
    A.setOption(PETSc.Mat.Option.NEW_NONZERO_LOCATION_ERR, False)
    A.setOption(PETSc.Mat.Option.NEW_NONZERO_LOCATIONS, False)
    A.setOption(PETSc.Mat.Option.IGNORE_ZERO_ENTRIES, True)
    return A


def flow_matrix(W: fem.FunctionSpace, field_names: list) -> PETSc.Mat:
    """Jacobian matrix of a fluid-alone Newton system: every (velocity, pressure) coupling of a cell and the
    diagonal of the mirrored mesh-displacement rows (whose rows and columns hold exact zeros otherwise)."""
    flow = [f for f in field_names if f != "displacement"]
    every_cell = np.arange(num_cells(W.mesh), dtype=np.int32)
    return pattern_matrix(W, field_names, [(every_cell, flow, flow)],
                          np.unique(cell_dofs(W, field_names, "displacement")))


def coupled_matrix(W: fem.FunctionSpace, field_names: list, fluid_cells: np.ndarray, solids: list,
                   part: str = "whole") -> PETSc.Mat:
    """Jacobian matrix of the coupled Newton system with the couplings of the module docstring; `solids`:
    [(local cells, Mooney-Rivlin?)] per solid region. `part`: "whole", "mesh" (the mesh-motion Jacobian: u <- u
    on fluid cells), "flow" (the urine's block: v, p <- v, p on fluid cells) or "wall" (the wall's rows along the
    kinematic direction, fsi.condensation: solid cells v, u, pi <- u, pi, `fluid_cells` v, p <- u, p), each with
    every diagonal."""
    flow = [f for f in ("velocity", "pressure") if f in field_names]
    pressure = [f for f in ("pressure",) if f in field_names]
    blocks = {"mesh": [(fluid_cells, ["displacement"], ["displacement"])],
              "flow": [(fluid_cells, flow, flow)]}.get(part)
    if part == "wall":
        blocks = [(fluid_cells, flow, ["displacement"] + pressure)]
        for cells, mooney_rivlin in solids:
            pi = ["solid_pressure"] if mooney_rivlin else []
            blocks.append((cells, ["velocity", "displacement"] + pi, ["displacement"] + pi))
    elif blocks is None:
        blocks = [(fluid_cells, ["displacement"], ["displacement"]), (fluid_cells, flow, flow + ["displacement"])]
        for cells, mooney_rivlin in solids:
            pi = ["solid_pressure"] if mooney_rivlin else []
            blocks += [(cells, ["velocity"], ["velocity", "displacement"] + pi),
                       (cells, ["displacement"], ["velocity", "displacement"]),
                       (cells, pi, ["displacement"] + pi)]
    imap, bs = W.dofmap.index_map, W.dofmap.index_map_bs
    return pattern_matrix(W, field_names, blocks, np.arange(imap.size_local * bs, dtype=np.int32))
