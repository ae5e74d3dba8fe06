"""Mesh-motion strategies of a fluid-alone scene (SolverOptions.mesh_motion_coupling: segregated): the ALE
displacement of the fluid mesh at the new time, found before the flow's Newton step (MonolithicFSI); and the
cell stiffness of every mesh-motion problem; MonolithicFSI's mesh-motion methods (MeshMotionMethods)."""
from __future__ import annotations

import contextlib
import math
import time as _time
from dataclasses import replace

import numpy as np
import ufl
from dolfinx import fem
from dolfinx.fem import petsc as fem_petsc
from mpi4py import MPI
from petsc4py import PETSc

from . import physics
from .linear_solvers import Mumps, direct_package, set_options

MISMATCH_LIMIT = 0.05       # PrescribedMap: largest disagreement with the boundary motion, of the displacement


def cell_stiffness(mesh, cells: np.ndarray, exponent: float) -> fem.Function:
    """DG0 k = (V_mean / V_cell)^exponent on the local `cells` (mean over them), 1 elsewhere: small cells near
    interfaces resist distortion."""
    Q = fem.FunctionSpace(mesh, ("DG", 0))
    vol = fem_petsc.assemble_vector(fem.form(ufl.TestFunction(Q) * ufl.dx(domain=mesh)))
    vol.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
    k = fem.Function(Q, name="mesh_stiffness")
    cells = cells[cells < mesh.topology.index_map(mesh.topology.dim).size_local]
    dofs = Q.dofmap.list.array[cells]          # one DG0 dof per cell, through the dofmap
    local = vol.array[dofs]
    vol.destroy()               # else kept in its communicator's garbage (fsi.release)
    total = mesh.comm.allreduce(local.sum(), MPI.SUM)
    count = mesh.comm.allreduce(local.size, MPI.SUM)
    vmean = total / max(count, 1)
    k.x.array[:] = 1.0
    k.x.array[dofs] = (vmean / local) ** exponent
    k.x.scatter_forward()
    return k


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
    operator is SPD; cheaper than smoothed-aggregation AMG, docs/performance.md)
    to `rtol` of the preconditioned right-hand side, started from the caller's guess; its iterations are
    counted in counters["mesh_motion_iterations"]."""
    mismatch = 0.0

    def __init__(self, displacement: fem.Function, bcs: list, a, L, comm, *, iterative: bool, package: str,
                 rtol: float, prefix: str, counters: dict, mumps: Mumps = Mumps()):
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
                set_options(prefix, mumps.options())
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


def segregated_motion(displacement: fem.Function, bcs: list, prescribed, ops, stiffness, dx_fluid, options,
                      prefix: str, counters: dict):
    """The segregated mesh motion into `displacement` with the Dirichlet conditions `bcs`: the `prescribed` ALE map
    (Scene.mesh_motion), or (None) the extension problem of SolverOptions.mesh_motion with the cell `stiffness`
    over `dx_fluid` (LU, or CG above `options.mesh_motion_direct_max_unknowns`)."""
    V = displacement.function_space
    comm = V.mesh.comm
    if prescribed is not None:
        return PrescribedMap(displacement, bcs, prescribed, comm)
    a = physics.mesh_motion_residual(ops, options.mesh_motion, ufl.TrialFunction(V), ufl.TestFunction(V),
                                     stiffness, dx_fluid)
    L = ufl.inner(fem.Constant(V.mesh, np.zeros(V.ufl_element().value_shape())), ufl.TestFunction(V)) * dx_fluid
    limit = options.mesh_motion_direct_max_unknowns
    unknowns = V.dofmap.index_map.size_global * V.dofmap.index_map_bs
    return Extension(displacement, bcs, a, L, comm, iterative=limit is not None and unknowns > limit,
                     package=direct_package(options.linear_solver), rtol=options.mesh_motion_rtol, prefix=prefix,
                     counters=counters, mumps=options.mumps())


class MeshMotionMethods:
    """The mesh-motion methods of MonolithicFSI (its base class): the segregated mesh motion of a fluid-alone scene,
    the monolithic mesh-motion rows, the smallest ALE Jacobian."""

    def _setup_mesh_motion(self):
        """The segregated mesh motion of the scene (mesh_motion.segregated_motion)."""
        self.mesh_motion = segregated_motion(self.mesh_displacement, self.constraints.mesh, self.scene.mesh_motion,
                                             self.ops, self.stiffness, self.dx(self.fluid_tags), self.options,
                                             f"{self.options_prefix}mesh_", self.counters)

    def use_mesh_motion(self, prescribed) -> None:
        """Swap the segregated mesh motion before a run: a prescribed ALE map (as Scene.mesh_motion) or None (the
        extension problem); the problem is otherwise the one a scene with that map poses."""
        if not self.segregated:
            raise ValueError("use_mesh_motion swaps the segregated mesh motion (mesh_motion_coupling 'segregated')")
        self.scene = replace(self.scene, mesh_motion=prescribed)
        self._setup_mesh_motion()

    @property
    def mesh_motion_solver(self) -> str:
        """How the segregated mesh motion is found: prescribed, lu or cg_icc."""
        return self.mesh_motion.name

    @property
    def mesh_motion_mismatch(self) -> float:
        """Largest disagreement of a prescribed ALE map with the boundary motion, of the displacement (0 else)."""
        return self.mesh_motion.mismatch

    def solve_mesh_motion(self):
        """Mesh displacement of the current time from the prescribed boundary displacement. An iterative solve
        starts from the linear extrapolation u_n + (dt/dt_prev)(u_n - u_n-1) of the mirrored history in x_n,
        x_nm1 (which checkpoints hold, so a resumed run starts from the same guess)."""
        t0 = _time.perf_counter()
        u_n, u_nm1 = self.x_n.x.array[self._mesh_dofs], self.x_nm1.x.array[self._mesh_dofs]
        w = float(self.dt.value) / self.dt_prev if self.dt_prev else 0.0
        self.mesh_motion.solve(float(self.t.value), u_n + w * (u_n - u_nm1))
        self.timings["mesh_motion"] += _time.perf_counter() - t0

    @contextlib.contextmanager
    def mesh_motion_preview(self):
        """A callable t -> the segregated mesh displacement the Dirichlet data of time t give (the run's own map at t,
        for a prediction before the run); on exit the displacement, the boundary data of the current time and the
        mesh motion's recorded mismatch are restored."""
        d, motion = self.mesh_displacement, self.mesh_motion
        saved, mismatch = d.x.array.copy(), motion.mismatch

        def at(t: float) -> fem.Function:
            self.constraints.update(t)
            motion.solve(t, d.x.array.copy())
            return d

        try:
            yield at
        finally:
            d.x.array[:] = saved
            motion.mismatch = mismatch
            self.constraints.update(self.time)

    def min_ale_jacobian(self) -> float:
        """Minimum det(I + Grad u) over the fluid mesh (1 when undeformed, <= 0 when inverted)."""
        return 1.0 if self.ale_jacobian is None else self.ale_jacobian.minimum()

    def min_ale_jacobian_at(self):
        """(minimum ALE Jacobian, reference coordinates (x, y, z) of its fluid vertex), reduced over ranks;
        a non-finite Jacobian counts as -inf (a scene without fluid: (1, NaN))."""
        return (1.0, (math.nan,) * 3) if self.ale_jacobian is None else self.ale_jacobian.minimum_at()

    def assemble_mesh_rows(self, out: PETSc.Vec) -> None:
        """The mesh-motion rows R_m(x) into `out` (owned entries; the removed rows 0): A_m x for a linear extension
        (harmonic or elastic, physics.mesh_motion_residual: linear in u without a source, so R_m(x) = A_m x, a
        product instead of an assembly), else (Jacobian-stiffened) assembled from their form."""
        if not self.options.mesh_jacobian_stiffening:
            self.mesh_motion_matrix().mult(self.x.vector, out)
            return
        with out.localForm() as loc:
            loc.set(0.0)
        fem_petsc.assemble_vector(out, self.mesh_form)
        out.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
        out.array_w[self.constraints.mesh_rows_local] = 0.0

    def mesh_motion_matrix(self) -> PETSc.Mat:
        """The mesh-motion rows' Jacobian (the interface's and Dirichlet rows removed) at the current state: a linear
        extension's assembled once, a Jacobian-stiffened one's (mesh_jacobian_stiffening > 0) at every call."""
        Am = self.Am
        if not self._mesh_jacobian_ready:
            Am.zeroEntries()
            fem_petsc.assemble_matrix(Am, self.mesh_jacobian_form)
            Am.assemble()
            Am.zeroRows(self.constraints.mesh_rows, diag=0.0)
            self._mesh_jacobian_ready = not self.options.mesh_jacobian_stiffening
        return Am
