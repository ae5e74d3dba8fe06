"""The solid block's LU with the velocity condensed out through the kinematic rows (exact static condensation).

On solid cells the kinematic residual (physics.kinematic_residual) int (du/dt - v) . psi makes, for each free
displacement dof u_i, a row J[U, V] = -M, J[U, U] = (b0/dt) M with the solids' mass matrix M: the velocity dof
v_i at the same node and component is paired with u_i. While these rows hold (r_U = 0), a correction keeps them
only if dv_i = (b0/dt) du_i, and the block's system J dx = r reduces, exactly, to its other rows Q in the other
unknowns R (everything but the paired velocities V):

    K dx_R = r_Q,   K = J[Q, R] along dv = (b0/dt) du,   dx_V = (b0/dt) dx_U,

K being the derivative of the wall's rows in the kinematic direction (dv, du) = ((b0/dt) du, du), a form of its
own (MonolithicFSI._partitioned): the displacement form of the solid's Newton system, about 60 % of the block's
unknowns and a sparser operator whose LU is a fraction of the whole block's (docs/performance.md). The cell
unknowns P (a P0 field, the solid pressure pi: K[P, P] is diagonal) are eliminated too, the rows Q \ P and the
unknowns R \ P ("o") left:

    K = [[A, B], [C, D]],   (A - B D^-1 C) dx_o = r_o - B D^-1 r_P,   dx_P = D^-1 (r_P - C dx_o),

a Schur complement with A's own sparsity (a cell unknown couples only the dofs of its cell), free of the mixed
u-pi saddle point: a smaller LU, fewer delayed pivots (docs/performance.md). The kinematic rows hold at a step's start (the paired velocities set nodally, partitioned.PartitionedCoupling.match_kinematics);
every condensed correction then keeps them (they are linear), and so does Anderson mixing (affine); how far a state
is from them is M^-1 r_U (`kinematic_correction`, a Cholesky factor of the constant M).
"""
from __future__ import annotations

import math

import basix
import numpy as np
from mpi4py import MPI
from petsc4py import PETSc

from .linear_solvers import Mumps, mumps_status, set_options
from .sparsity import cell_dofs

KINEMATIC_RTOL = 1e-10        # the condensed operator's kinematic rows vanish to this part of (b0/dt) ||M||


def direct(comm, prefix: str, kind: str, mumps: Mumps) -> PETSc.KSP:
    """A KSP applying a MUMPS factorisation (`kind` "lu" or "cholesky", made as `mumps` says) of its operator."""
    ksp = PETSc.KSP().create(comm)
    ksp.setOptionsPrefix(prefix)
    set_options(prefix, {"ksp_type": "preonly", "pc_type": kind, "pc_factor_mat_solver_type": "mumps"}
                | mumps.options())
    ksp.setFromOptions()
    return ksp


def kinematic_pairs(problem, solid_split: np.ndarray) -> tuple[np.ndarray, np.ndarray, int]:
    """(positions in `solid_split` of the paired velocity dofs, of their displacement dofs, the number of pairs left
    whole because one of the two is constrained and the other not): the pairs (v_i, u_i) at the same node and
    component of the solid cells, both unconstrained, both owned."""
    cells = problem.cells(problem.solid_tags)
    v, u = (cell_dofs(problem.W, problem.field_names, f)[cells].ravel() for f in ("velocity", "displacement"))
    v, first = np.unique(v, return_index=True)
    u = u[first]
    cv, cu = np.isin(v, problem.constraints.constrained), np.isin(u, problem.constraints.constrained)
    owned = np.isin(v, solid_split) & np.isin(u, solid_split)
    keep = owned & ~cv & ~cu
    mismatched = int(np.count_nonzero(owned & (cv != cu)))
    return np.searchsorted(solid_split, v[keep]), np.searchsorted(solid_split, u[keep]), mismatched


def mass_eigenvalue_floor(problem, cells: np.ndarray) -> float:
    """A lower bound of the smallest eigenvalue of the solids' kinematic mass matrix M = int w v . psi over the
    local `cells` (w = 1, or 2 pi r in r-z): x^T M x = sum_K x_K^T M_K x_K >= min_K lambda_min(M_K) |x|^2 (each
    dof lies in a cell; a principal submatrix's smallest eigenvalue is not smaller), and on an affine simplex
    M_K >= |det J_K| min_K(w) M_ref, M_ref the reference cell's scalar mass matrix of the velocity's element (w is
    linear in r: its minimum at a vertex). 0 (no bound) for a curved geometry or a cell that is not a simplex."""
    mesh = problem.mesh
    cell = mesh.ufl_cell().cellname()
    local = math.inf
    if mesh.geometry.cmap.degree == 1 and cell in ("triangle", "tetrahedron") and cells.size:
        element = basix.create_element(basix.ElementFamily.P, basix.cell.string_to_type(cell),
                                       problem.options.velocity_degree, basix.LagrangeVariant.gll_warped)
        points, weights = basix.make_quadrature(basix.cell.string_to_type(cell), 2 * element.degree)
        phi = element.tabulate(0, points)[0, :, :, 0]
        reference = np.linalg.eigvalsh(phi.T @ (weights[:, None] * phi)).min()
        tdim = mesh.topology.dim
        nodes = mesh.geometry.x[mesh.geometry.dofmap.array.reshape(-1, tdim + 1)[cells], :tdim]
        det = np.abs(np.linalg.det(nodes[:, 1:] - nodes[:, :1]))
        weight = 2.0 * math.pi * nodes[:, :, 0].min(axis=1) if problem.ops.axisymmetric else 1.0
        local = float((det * weight).min()) * reference
    elif cells.size:
        local = 0.0
    bound = problem.comm.allreduce(local, op=MPI.MIN)
    return 0.0 if not math.isfinite(bound) else max(bound, 0.0)


class CondensedSolidFactor:
    """The interface of block_factors.BlockFactor for the solid block, condensed as in the module docstring.
    `solid_split`: the block's owned local dofs (sorted); `offset`: the global index of local dof 0; `v_pos`,
    `u_pos`: kinematic_pairs; `mass`: a matrix on the mixed space holding M in its (U, V) entries; `mass_floor`:
    a lower bound of M's smallest eigenvalue (mass_eigenvalue_floor; 0: none); `cell_pos`: positions in the split of
    the cell unknowns (P0), eliminated cell by cell."""

    def __init__(self, comm, prefix: str, mumps: Mumps, solid_split: np.ndarray, offset: int,
                 v_pos: np.ndarray, u_pos: np.ndarray, mass: PETSc.Mat, mass_floor: float = 0.0,
                 cell_pos: np.ndarray | None = None):
        n = len(solid_split)
        self.mass_floor = float(mass_floor)
        self.v_pos, self.u_pos = v_pos, u_pos
        self.r_pos = np.setdiff1d(np.arange(n), v_pos)
        self.q_pos = np.setdiff1d(np.arange(n), u_pos)
        self.paired_in_r = np.searchsorted(self.r_pos, u_pos)       # u_i's place among the unknowns R
        # the cell unknowns P (positions among Q and among R) and the others
        cell = np.zeros(n, bool)
        cell[np.zeros(0, np.int32) if cell_pos is None else cell_pos] = True
        self.q_cell, self.q_rest = np.flatnonzero(cell[self.q_pos]), np.flatnonzero(~cell[self.q_pos])
        self.r_cell, self.r_rest = np.flatnonzero(cell[self.r_pos]), np.flatnonzero(~cell[self.r_pos])
        self.eliminates_cells = comm.allreduce(len(self.r_cell)) > 0
        g = (solid_split + offset).astype(PETSc.IntType)
        self.comm = comm
        self.IV, self.IU, self.IR, self.IQ = (PETSc.IS().createGeneral(g[p], comm=comm)
                                              for p in (v_pos, u_pos, self.r_pos, self.q_pos))
        self.operator = None              # J[Q, R], in its own numbering (rows Q, columns R in the split's order)
        self.IQo = self.IRo = self.IPq = self.IPr = None
        self.ksp, self.mass_ksp = (direct(comm, f"{prefix}{p}", kind, mumps)
                                   for p, kind in (("", "lu"), ("mass_", "cholesky")))
        self.M = mass.createSubMatrix(self.IU, self.IV)
        self.M.setOption(PETSc.Mat.Option.SYMMETRIC, True)
        self.mass_ksp.setOperators(self.M)
        self.mass_ksp.setUp()
        self.mass_ksp.getPC().setUp()
        self.K = None                     # the operator factorised: K, or its Schur complement A - B D^-1 C
        self.B = self.C = self.D = self.BC = self.dinv = None
        self.rate = None
        self.sizes = {"paired velocities": comm.allreduce(len(v_pos)),
                      "cell unknowns": comm.allreduce(len(self.r_cell)), "condensed": comm.allreduce(len(self.r_rest))}
        self.rhs = self.dxR = None
        self.rhs_u, self.y = self.M.createVecLeft(), self.M.createVecRight()
        self.dx = np.zeros(len(self.r_pos))

    def refresh(self, matrix: PETSc.Mat, index: PETSc.IS, rate: float) -> None:
        """Factorise K = matrix[Q, R] (the operator, kept), or its Schur complement over the cell unknowns (`matrix`:
        the wall rows' Jacobian along the kinematic direction at b0/dt = `rate`); at the first, check that the
        kinematic rows vanish along it (else the pairing is not the form's)."""
        if self.operator is None:
            self.check_kinematic_rows(matrix, rate)
            self.operator = matrix.createSubMatrix(self.IQ, self.IR)
            first_q, first_r = self.operator.getOwnershipRange()[0], self.operator.getOwnershipRangeColumn()[0]
            self.IQo, self.IRo, self.IPq, self.IPr = (
                PETSc.IS().createGeneral((first + p).astype(PETSc.IntType), comm=self.comm)
                for first, p in ((first_q, self.q_rest), (first_r, self.r_rest), (first_q, self.q_cell),
                                 (first_r, self.r_cell)))
        else:
            matrix.createSubMatrix(self.IQ, self.IR, submat=self.operator)
        self.factorise(self.operator, rate)

    def factorise(self, operator: PETSc.Mat, rate: float) -> None:
        """Factorise `operator` (J[Q, R]: the one kept, with the values of refresh or of an assembly straight into it,
        fsi.block_jacobian), or its Schur complement over the cell unknowns."""
        if operator is not self.operator:
            raise ValueError("the condensed factor refactorises its own operator, J[Q, R]")
        if self.eliminates_cells:
            self.eliminate_cells(self.operator)
        else:
            self.K = self.operator
        self.ksp.setOperators(self.K)
        self.ksp.getPC().setReusePreconditioner(False)
        self.ksp.setUp()
        self.ksp.getPC().setUp()          # factorise now (KSP's own set-up would leave it to the first solve)
        self.rate = rate
        if self.dxR is None:
            self.rhs, self.dxR = self.K.createVecLeft(), self.K.createVecRight()
            self.cell_rhs = self.C.createVecLeft() if self.eliminates_cells else None

    def eliminate_cells(self, matrix: PETSc.Mat) -> None:
        """K = A - B D^-1 C of `matrix` (J[Q, R], module docstring), B kept scaled as B D^-1. D is diagonal for a P0
        field of cell-local forms; were it not, the solve would be inexact, not wrong: the sweeps converge to the
        residual's fixed point whatever the blocks' operators."""
        self.K = matrix.createSubMatrix(self.IQo, self.IRo, submat=self.K)
        self.B = matrix.createSubMatrix(self.IQo, self.IPr, submat=self.B)
        self.C = matrix.createSubMatrix(self.IPq, self.IRo, submat=self.C)
        self.D = matrix.createSubMatrix(self.IPq, self.IPr, submat=self.D)
        self.dinv = self.D.getDiagonal(self.dinv)
        self.dinv.reciprocal()
        self.B.diagonalScale(None, self.dinv)
        self.BC = self.B.matMult(self.C, result=self.BC)
        self.K.axpy(-1.0, self.BC, structure=PETSc.Mat.Structure.SUBSET_NONZERO_PATTERN)

    def check_kinematic_rows(self, matrix: PETSc.Mat, rate: float) -> None:
        """||matrix[U, R]|| <= KINEMATIC_RTOL (b0/dt) ||M||: along dv = (b0/dt) du the kinematic rows cancel."""
        rows = matrix.createSubMatrix(self.IU, self.IR)
        off, size = rows.norm(PETSc.NormType.FROBENIUS), max(rate, 1.0) * self.M.norm(PETSc.NormType.FROBENIUS)
        rows.destroy()
        if off > KINEMATIC_RTOL * size:
            raise RuntimeError(f"the solid block's kinematic rows do not cancel along dv = (b0/dt) du "
                               f"(||J[U, R]|| = {off:.2e} of {size:.2e}): the velocity-displacement pairing is wrong")

    def solve(self, b: PETSc.Vec, x: PETSc.Vec) -> str:
        """x = J_SS^-1 b (both in the solid split's layout) for b whose kinematic rows vanish; returns why it
        failed ("" if it did not)."""
        rhs = b.array_r[self.q_pos]
        if self.eliminates_cells:
            r_cell = rhs[self.q_cell]
            self.cell_rhs.array[:] = r_cell
            self.B.mult(self.cell_rhs, self.rhs)                          # B D^-1 r_P
            self.rhs.array[:] = rhs[self.q_rest] - self.rhs.array_r
        else:
            self.rhs.array[:] = rhs
        self.ksp.solve(self.rhs, self.dxR)
        reason = self.ksp.getConvergedReason()
        if reason < 0:
            return f"LU failed (PETSc KSP reason {reason}{mumps_status(self.ksp.getPC().getFactorMatrix())})"
        dx = self.dx
        if self.eliminates_cells:
            dx[self.r_rest] = self.dxR.array_r
            self.C.mult(self.dxR, self.cell_rhs)
            dx[self.r_cell] = self.dinv.array_r * (r_cell - self.cell_rhs.array_r)
        else:
            dx[:] = self.dxR.array_r
        xa = x.array
        xa[self.r_pos] = dx
        xa[self.v_pos] = self.rate * dx[self.paired_in_r]
        return ""

    def kinematic_correction(self, b: np.ndarray) -> np.ndarray:
        """M^-1 r_U of the block's residual b (the solid split's owned entries): added to the paired velocities, it
        makes the kinematic rows hold (r_U = M (b0/dt u + ... - v))."""
        self.rhs_u.array[:] = b[self.u_pos]
        self.mass_ksp.solve(self.rhs_u, self.y)
        return self.y.array_r.copy()
