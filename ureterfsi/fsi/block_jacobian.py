"""A block's Jacobian assembled straight into the block's operator from a form on the block's own fields.

The partitioned scheme (fsi.partitioned) factorises blocks J[rows, cols] of the Newton matrix on the mixed space W:
the wall's condensed operator K = J[Q, R] (fsi.condensation: velocity and solid-pressure rows, displacement and
solid-pressure columns) and the urine's J[F, F] (velocity and pressure). Assembled on W, each cell inserts the mixed
element's whole dense matrix (65 x 65 on a P2-P2-P1-P0 tetrahedron), although the block keeps 31 x 31 (the wall)
or 34 x 34 (the urine) of it: the other rows and columns belong to other blocks, are zero (the velocity direction of
the wall's Jacobian, folded into the displacement's) or are identities of constrained dofs. Here the same form is
posed with test and trial functions of spaces of the block's fields alone (`field_space`: W's sub-elements, mixed)
and inserted through local-to-global maps that send each dof to its row or column of the block's operator, or to
-1 (skipped by PETSc's MatSetValues) where it is outside the block or constrained; the constrained dofs' identity
entries, which assembling on W with its conditions makes, are added. The same operator entry for entry, from a
fraction of the insertions (docs/performance.md).
"""
from __future__ import annotations

import numpy as np
import ufl
from dolfinx import fem
from dolfinx.fem import petsc as fem_petsc
from petsc4py import PETSc

from .sparsity import cell_dofs

CHECK_RTOL = 1e-10     # ||J_block - J[rows, cols]||_F within this part of ||J[rows, cols]||_F at the first refresh


def field_space(W: fem.FunctionSpace, field_names: list, names: list) -> tuple[fem.FunctionSpace, np.ndarray]:
    """The space of the fields `names` of W (their sub-elements of W, mixed) and the map of its local dofs (ghosts
    included) to W's."""
    elements = W.ufl_element().sub_elements()
    V = fem.FunctionSpace(W.mesh, ufl.MixedElement([elements[field_names.index(n)] for n in names]))
    to_W = np.full(V.dofmap.index_map.size_local + V.dofmap.index_map.num_ghosts, -1, dtype=np.int64)
    for name in names:
        to_W[cell_dofs(V, names, name)] = cell_dofs(W, field_names, name)
    if (to_W < 0).any():
        raise RuntimeError(f"field_space {names}: {int((to_W < 0).sum())} dofs on no cell")
    return V, to_W


def field_components(V: fem.FunctionSpace, names: list, argument) -> dict:
    """{field: [its components]} of the test or trial function (`argument`: ufl.TestFunction or ufl.TrialFunction)
    of V = field_space(..., names)."""
    parts = ufl.split(argument(V))
    return {n: ([p[i] for i in range(p.ufl_shape[0])] if p.ufl_shape else [p]) for n, p in zip(names, parts)}


class BlockJacobian:
    """Assembles `form` (a bilinear form on field spaces, field_space) into a block's operator A = J[rows, cols]:
    `row_to_W`, `col_to_W` map the form's test and trial dofs to W's. `bind` fixes the operator (made once by
    extracting the block of the Jacobian on W, whose structure it keeps) and the block's numbering; `check` compares
    an assembly with the operator's values extracted from W's Jacobian."""

    def __init__(self, form: fem.Form, row_to_W: np.ndarray, col_to_W: np.ndarray):
        self.form, self.row_to_W, self.col_to_W = form, row_to_W, col_to_W
        self.operator = None
        self.identity = None

    def bind(self, problem, operator: PETSc.Mat, split: np.ndarray, row_pos: np.ndarray, col_pos: np.ndarray,
             constrained: np.ndarray) -> None:
        """`operator`: the block's matrix (its rows the split's positions `row_pos`, its columns `col_pos`, in order,
        from the split's owned local dofs `split` of W); `constrained`: W's local dofs (ghosts included) whose rows
        and columns are identities (problem.bcs)."""
        first_row, first_col = operator.getOwnershipRange()[0], operator.getOwnershipRangeColumn()[0]
        rows = self.numbering(problem, split[row_pos], first_row, constrained)
        cols = self.numbering(problem, split[col_pos], first_col, constrained)
        comm = operator.getComm()
        operator.setLGMap(PETSc.LGMap().create(rows[self.row_to_W].astype(PETSc.IntType), comm=comm),
                          PETSc.LGMap().create(cols[self.col_to_W].astype(PETSc.IntType), comm=comm))
        operator.setOption(PETSc.Mat.Option.NEW_NONZERO_LOCATION_ERR, True)
        operator.setOption(PETSc.Mat.Option.IGNORE_ZERO_ENTRIES, True)
        # the identities: constrained owned dofs of the split, in both the rows and the columns
        owned = np.intersect1d(split, constrained)
        in_rows, in_cols = np.isin(owned, split[row_pos]), np.isin(owned, split[col_pos])
        if not np.array_equal(in_rows, in_cols):
            raise RuntimeError("a constrained dof of the block is among its rows but not its columns, or the reverse")
        owned = owned[in_rows]
        self.identity = tuple((first + np.searchsorted(split[pos], owned)).astype(PETSc.IntType)[:, None]
                              for first, pos in ((first_row, row_pos), (first_col, col_pos)))
        self.operator = operator

    @staticmethod
    def numbering(problem, dofs: np.ndarray, first: int, constrained: np.ndarray) -> np.ndarray:
        """Per local dof of W (ghosts included): its index in the block's global numbering (owned `dofs` numbered
        first, first + 1, ... in order, on every rank), -1 where it is not in the block or is constrained."""
        marker = fem.Function(problem.W)
        marker.x.array[:] = -1.0
        marker.x.array[dofs] = first + np.arange(len(dofs), dtype=np.float64)
        marker.x.scatter_forward()
        index = np.rint(marker.x.array).astype(np.int64)
        index[constrained] = -1
        return index

    def assemble(self) -> PETSc.Mat:
        """The operator's values at the current state: the form's entries and the identities."""
        A = self.operator
        A.zeroEntries()
        fem_petsc.assemble_matrix(A, self.form)
        rows, cols = self.identity
        A.setValuesRCV(rows, cols, np.ones((len(rows), 1), dtype=PETSc.ScalarType), addv=PETSc.InsertMode.ADD)
        A.assemble()
        return A

    def check(self, name: str) -> None:
        """Assemble, and compare with the operator's values before (extracted from W's Jacobian at the same state):
        a RuntimeError names the difference where the two are not the same operator."""
        extracted = self.operator.copy()
        try:
            self.assemble()
        except PETSc.Error as error:
            raise RuntimeError(f"the {name} block's Jacobian on its own fields puts entries outside its block of the "
                               f"Jacobian on the mixed space (PETSc error {error.ierr}): the field spaces' dof maps "
                               f"are wrong") from error
        extracted.axpy(-1.0, self.operator, structure=PETSc.Mat.Structure.SAME_NONZERO_PATTERN)
        off = extracted.norm(PETSc.NormType.FROBENIUS)
        size = self.operator.norm(PETSc.NormType.FROBENIUS)
        extracted.destroy()
        if not off <= CHECK_RTOL * size:
            raise RuntimeError(f"the {name} block's Jacobian on its own fields differs from its block of the Jacobian "
                               f"on the mixed space (||difference|| = {off:.2e} of {size:.2e}): the field spaces' dof "
                               f"maps are wrong")
