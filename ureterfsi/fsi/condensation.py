"""The solid block's LU with the velocity condensed out through the kinematic rows (exact static condensation).

On solid cells the kinematic residual (physics.kinematic_residual) int (du/dt - v) . psi gives, for each free
displacement dof u_i, a row J[U, V] = -M, J[U, U] = (b0/dt) M with the same mass matrix M: the velocity dof v_i at
the same node and component is paired with u_i (P: unknowns R -> eliminated velocities V). With the other rows Q
and unknowns R (everything but V), the block's correction J dx = r is, exactly,

    y = M^-1 r_U,      (J[Q, R] + (b0/dt) J[Q, V] P) dx_R = r_Q + J[Q, V] y,      dx_V = (b0/dt) P dx_R - y,

the displacement form of the solid's Newton system: about 60 % of the block's unknowns, a sparser operator, and
an LU a fraction of the whole block's (docs/performance.md). M^-1 is a Cholesky factor (MUMPS) of the mass matrix;
J[U, R] = (b0/dt) M P is checked at every refactorisation.
"""
from __future__ import annotations

import numpy as np
from mpi4py import MPI
from petsc4py import PETSc

from .linear_solvers import mumps_options

PAIRING_RTOL = 1e-10               # J[U, R] = (b0/dt) M P to this relative Frobenius norm


def kinematic_pairs(problem, solid_split: np.ndarray) -> tuple[np.ndarray, np.ndarray, int]:
    """(positions in `solid_split` of the eliminated velocity dofs, of their paired displacement dofs, the number
    of pairs left whole because one of the two is constrained and the other not): the pairs (v_i, u_i) at the same
    node and component of the solid cells, both unconstrained, v_i owned."""
    cells = problem.cells(problem.solid_tags)
    v_map, u_map = problem.sub("velocity").dofmap, problem.sub("displacement").dofmap
    v = np.concatenate([v_map.cell_dofs(c) for c in cells]) if len(cells) else np.zeros(0, np.int32)
    u = np.concatenate([u_map.cell_dofs(c) for c in cells]) if len(cells) else np.zeros(0, np.int32)
    v, first = np.unique(v, return_index=True)
    u = u[first]
    constrained = np.concatenate([np.zeros(0, np.int32)] + [bc.dof_indices()[0] for bc in problem.bcs])
    cv, cu = np.isin(v, constrained), np.isin(u, constrained)
    owned = np.isin(v, solid_split) & np.isin(u, solid_split)
    keep = owned & ~cv & ~cu
    mismatched = int(np.count_nonzero(owned & (cv != cu)))
    return np.searchsorted(solid_split, v[keep]), np.searchsorted(solid_split, u[keep]), mismatched


def direct(comm, prefix: str, kind: str, workspace_percent: int) -> PETSc.KSP:
    """A KSP applying a MUMPS factorisation (`kind` "lu" or "cholesky") of its operator."""
    ksp = PETSc.KSP().create(comm)
    ksp.setOptionsPrefix(prefix)
    o = PETSc.Options()
    for key, value in ({"ksp_type": "preonly", "pc_type": kind, "pc_factor_mat_solver_type": "mumps"}
                       | mumps_options(workspace_percent)).items():
        o[f"{prefix}{key}"] = value
    ksp.setFromOptions()
    return ksp


class CondensedSolidFactor:
    """The interface of partitioned.BlockFactor for the solid block, with the condensation of the module docstring.
    `solid_split`: the block's owned local dofs (sorted); `offset`: the global index of local dof 0."""

    def __init__(self, comm, prefix: str, workspace_percent: int, solid_split: np.ndarray, offset: int,
                 v_pos: np.ndarray, u_pos: np.ndarray):
        self.comm = comm
        n = len(solid_split)
        self.v_pos, self.u_pos = v_pos, u_pos
        self.r_pos = np.setdiff1d(np.arange(n), v_pos)
        self.q_pos = np.setdiff1d(np.arange(n), u_pos)
        g = (solid_split + offset).astype(PETSc.IntType)

        def index(pos):
            return PETSc.IS().createGeneral(g[pos], comm=comm)

        self.IV, self.IU, self.IR, self.IQ = index(v_pos), index(u_pos), index(self.r_pos), index(self.q_pos)
        nv, nr = len(v_pos), len(self.r_pos)
        r_start = comm.exscan(nr) or 0
        # P: R -> V, P[i, j] = 1 where R's entry j is the displacement paired with velocity i
        cols = (r_start + np.searchsorted(self.r_pos, u_pos)).astype(PETSc.IntType)
        self.P = PETSc.Mat().createAIJ(((nv, None), (nr, None)), comm=comm,
                                       csr=(np.arange(nv + 1, dtype=PETSc.IntType), cols, np.ones(nv)))
        self.ksp, self.mass_ksp = (direct(comm, f"{prefix}{p}", kind, workspace_percent)
                                   for p, kind in (("", "lu"), ("mass_", "cholesky")))
        self.K = self.JQV = self.JQR = self.QVP = self.M = None
        self.rate = None
        self.sizes = {"eliminated": comm.allreduce(nv), "condensed": comm.allreduce(nr)}
        self.work = {"rQ": None}

    def refresh(self, matrix: PETSc.Mat, index: PETSc.IS, rate: float) -> None:
        """Form and factorise the condensed operator from the Jacobian `matrix` (`index`: the solid split's IS);
        its pattern is kept from the first refresh (MUMPS then refactorises numerically only)."""
        first = self.K is None
        self.JQV = matrix.createSubMatrix(self.IQ, self.IV, submat=self.JQV)
        self.M = matrix.createSubMatrix(self.IU, self.IV, submat=self.M)
        self.M.scale(-1.0)
        self.M.setOption(PETSc.Mat.Option.SYMMETRIC, True)
        if first:
            self.check_pairing(matrix, rate)
        self.JQR = matrix.createSubMatrix(self.IQ, self.IR, submat=self.JQR)
        self.QVP = self.JQV.matMult(self.P, result=self.QVP)
        if first:
            self.K = self.JQR.duplicate(copy=True)
            self.K.axpy(rate, self.QVP, structure=PETSc.Mat.Structure.DIFFERENT_NONZERO_PATTERN)
            self.ksp.setOperators(self.K)
            self.mass_ksp.setOperators(self.M)
        else:
            self.K.zeroEntries()
            self.K.axpy(1.0, self.JQR, structure=PETSc.Mat.Structure.SUBSET_NONZERO_PATTERN)
            self.K.axpy(rate, self.QVP, structure=PETSc.Mat.Structure.SUBSET_NONZERO_PATTERN)
        for ksp in (self.ksp, self.mass_ksp):   # factorise now (KSP's own set-up would leave it to the first solve)
            ksp.setUp()
            ksp.getPC().setUp()
        self.rate = rate
        if self.work["rQ"] is None:
            self.work = {"rQ": self.K.createVecLeft(), "xR": self.K.createVecRight(), "rU": self.M.createVecLeft(),
                         "y": self.M.createVecRight(), "w": self.M.createVecRight()}

    def check_pairing(self, matrix: PETSc.Mat, rate: float) -> None:
        """J[U, R] = (b0/dt) M P, or the condensation would not be exact."""
        JUR = matrix.createSubMatrix(self.IU, self.IR)
        MP = self.M.matMult(self.P)
        JUR.axpy(-rate, MP, structure=PETSc.Mat.Structure.DIFFERENT_NONZERO_PATTERN)
        off, size = JUR.norm(PETSc.NormType.FROBENIUS), MP.norm(PETSc.NormType.FROBENIUS) * max(rate, 1.0)
        JUR.destroy()
        MP.destroy()
        if off > PAIRING_RTOL * size:
            raise RuntimeError(f"the solid block's kinematic rows do not pair velocity and displacement "
                               f"(||J[U, R] - (b0/dt) M P|| = {off:.2e} of {size:.2e}): condensation invalid")

    def solve(self, b: PETSc.Vec, x: PETSc.Vec) -> str:
        """x = J_SS^-1 b (both in the solid split's layout); returns why it failed ("" if it did not)."""
        w = self.work
        ba = b.array_r
        w["rU"].array[:] = ba[self.u_pos]
        w["rQ"].array[:] = ba[self.q_pos]
        self.mass_ksp.solve(w["rU"], w["y"])
        if self.mass_ksp.getConvergedReason() < 0:
            return f"mass-matrix Cholesky solve failed (PETSc KSP reason {self.mass_ksp.getConvergedReason()})"
        self.JQV.multAdd(w["y"], w["rQ"], w["rQ"])
        self.ksp.solve(w["rQ"], w["xR"])
        reason = self.ksp.getConvergedReason()
        if reason < 0:
            f = self.ksp.getPC().getFactorMatrix()
            return (f"LU failed (PETSc KSP reason {reason}; MUMPS INFOG(1) = {f.getMumpsInfog(1)}, "
                    f"INFOG(2) = {f.getMumpsInfog(2)}: -8/-9/-13 workspace or memory, -10 singular)")
        self.P.mult(w["xR"], w["w"])
        xa = x.array
        xa[self.r_pos] = w["xR"].array_r
        xa[self.v_pos] = self.rate * w["w"].array_r - w["y"].array_r
        return ""
