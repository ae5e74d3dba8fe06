"""Mesh-motion strategies of a fluid-alone scene (SolverOptions.mesh_motion_coupling: segregated): the ALE
displacement of the fluid mesh at the new time, found before the flow's Newton step (MonolithicFSI)."""
from __future__ import annotations

import numpy as np
from dolfinx import fem
from dolfinx.fem import petsc as fem_petsc
from mpi4py import MPI
from petsc4py import PETSc

from .linear_solvers import MUMPS_WORKSPACE_PERCENT, mumps_options

MISMATCH_LIMIT = 0.05       # PrescribedMap: largest disagreement with the boundary motion, of the displacement


class PrescribedMap:
    """The scene's closed-form ALE map d(x, t) (Scene.mesh_motion), interpolated; the displacement Dirichlet
    values then set on their dofs. Their largest disagreement relative to the largest displacement so far is
    kept in `mismatch` (a map that ignores the boundary motion is an error of the scene)."""
    name = "prescribed"

    def __init__(self, displacement: fem.Function, bcs: list, motion, comm):
        self.displacement, self.bcs, self.motion, self.comm = displacement, bcs, motion, comm
        self.mismatch = 0.0

    def solve(self, t: float, guess: np.ndarray) -> None:
        d = self.displacement
        d.interpolate(lambda x: self.motion(x, t))
        before = d.x.array.copy()
        fem_petsc.set_bc(d.vector, self.bcs)
        d.x.scatter_forward()
        scale = self.comm.allreduce(float(np.abs(d.x.array).max(initial=0.0)), MPI.MAX)
        if scale > 0.0:
            gap = self.comm.allreduce(float(np.abs(d.x.array - before).max(initial=0.0)), MPI.MAX) / scale
            self.mismatch = max(self.mismatch, gap)
            if gap > MISMATCH_LIMIT:
                raise ValueError(f"Scene.mesh_motion disagrees with the displacement Dirichlet conditions by {gap:.1%} "
                                 f"of the largest displacement at t = {t:g} s")


class Extension:
    """The linear extension problem a(d, psi) = 0 with the boundary displacement as Dirichlet data (the
    stiffened vector Laplacian or elasticity of SolverOptions.mesh_motion), assembled once. `iterative`
    False: LU by `package`, factorised once (`lu`); True: conjugate gradients with ICC(0) (`cg_icc`; the
    operator is SPD; cheaper here than smoothed-aggregation AMG: 0.7 vs 1.5 s per solve on the coarse model 3)
    to `rtol` of the preconditioned right-hand side, started from the caller's guess; its iterations are
    counted in counters["mesh_motion_iterations"]."""
    mismatch = 0.0

    def __init__(self, displacement: fem.Function, bcs: list, a, L, comm, *, iterative: bool, package: str,
                 rtol: float, prefix: str, counters: dict, workspace_percent: int = MUMPS_WORKSPACE_PERCENT):
        self.displacement, self.bcs, self.counters = displacement, bcs, counters
        self.a, self.L = fem.form(a), fem.form(L)
        A = fem_petsc.assemble_matrix(self.a, bcs=bcs)
        A.assemble()
        self.A, self.b = A, fem_petsc.create_vector(self.L)
        self.ksp = ksp = PETSc.KSP().create(comm)
        ksp.setOperators(A)
        self.name = "cg_icc" if iterative else "lu"
        if iterative:
            ksp.setType("cg")
            ksp.setTolerances(rtol=rtol, atol=0.0, max_it=2000)
            ksp.setInitialGuessNonzero(True)
            ksp.getPC().setType("icc")
            counters["mesh_motion_iterations"] = 0
        else:
            ksp.setType("preonly")
            ksp.getPC().setType("lu")
            ksp.getPC().setFactorSolverType(package)
            if package == "mumps":
                ksp.setOptionsPrefix(prefix)
                o = PETSc.Options()
                for key, value in mumps_options(workspace_percent).items():
                    o[f"{prefix}{key}"] = value
                ksp.setFromOptions()

    def solve(self, t: float, guess: np.ndarray) -> None:
        if self.name == "cg_icc":
            self.displacement.x.array[:] = guess
        b = self.b
        with b.localForm() as loc:
            loc.set(0.0)
        fem_petsc.apply_lifting(b, [self.a], [self.bcs])
        b.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
        fem_petsc.set_bc(b, self.bcs)
        self.ksp.solve(b, self.displacement.vector)
        if self.name == "cg_icc":
            self.counters["mesh_motion_iterations"] += self.ksp.getIterationNumber()
        if self.ksp.getConvergedReason() < 0:
            raise RuntimeError(f"mesh-motion solve failed: PETSc KSP reason {self.ksp.getConvergedReason()} "
                               f"after {self.ksp.getIterationNumber()} CG iterations")
        self.displacement.x.scatter_forward()
