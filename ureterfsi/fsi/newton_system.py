"""MonolithicFSI's Newton system: the assembly of the residual R(x) and the Jacobian J (with the segregated
or coupled mesh-motion rows), whether a kept factorisation is of this step's operator, the correction J^-1 R, and
`newton`: one step's R(x) = 0 by Newton's method (fsi.newton), the linearly implicit step (fsi.linearly_implicit,
with Newton as its fallback) or the partitioned sweeps (fsi.partitioned)."""
from __future__ import annotations

import logging
import math
import time as _time

from dolfinx.fem import petsc as fem_petsc
from petsc4py import PETSc

from .newton import NewtonDivergence

log = logging.getLogger("ureterfsi.fsi")


class NewtonSystemMethods:
    """MonolithicFSI's methods that pose and solve one step's Newton system (mixed into MonolithicFSI: they use its
    forms, vectors, solvers, timings and counters)."""

    def _assemble_residual(self):
        t0 = _time.perf_counter()
        if self.end_conditions:
            self.end_conditions.update()
        b = self.b
        with b.localForm() as loc:
            loc.set(0.0)
        fem_petsc.assemble_vector(b, self.residual_form)
        if self.mesh_form is not None:
            self.assemble_mesh_rows(self.bm)
        b.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
        b.copy(self._b_free)       # the physics residual before constraints: after a converged step, the reaction
        if self.mesh_form is not None:
            b.axpy(1.0, self.bm)
        fem_petsc.set_bc(b, self.bcs, self.x.vector, -1.0)
        self.timings["assemble_residual"] += _time.perf_counter() - t0
        return b.norm()

    def _assemble_jacobian(self):
        t0 = _time.perf_counter()
        A = self.A
        A.zeroEntries()
        fem_petsc.assemble_matrix(A, self.jacobian_form, bcs=self.bcs)
        A.assemble()
        if self.mesh_jacobian_form is not None:
            A.axpy(1.0, self.mesh_motion_matrix(), structure=PETSc.Mat.Structure.SUBSET_NONZERO_PATTERN)
        self._jacobian_valid = True
        self._jacobian_rate = self._rate()
        self.timings["assemble_jacobian"] += _time.perf_counter() - t0

    def _rate(self) -> float:
        """b0/dt, the only time-integration coefficient in the Jacobian (0 in steady solves)."""
        return float(self.bdf[0].value) / float(self.dt.value)

    def _jacobian_current(self) -> bool:
        """A kept factorisation is only reusable for the same b0/dt: a steady-state Jacobian (no inertia)
        or one of another step size or BDF order would be reused for a different operator."""
        return self._jacobian_valid and math.isclose(self._jacobian_rate, self._rate(), rel_tol=1e-12)

    def jacobian_kept(self) -> bool:
        """A factorisation is kept (of any b0/dt: as a preconditioner, fsi.linearly_implicit)."""
        return self._jacobian_valid

    def invalidate_jacobian(self):
        """Force a fresh Jacobian and factorisation (of every block) at the next Newton iteration."""
        self._jacobian_valid = False
        self.linear_solver.invalidate()
        if self.partitioned is not None:
            self.partitioned.invalidate()

    def _newton_correction(self, fresh: bool, rtol: float) -> str | None:
        """dx_vec = J^-1 b to relative tolerance rtol, with a fresh Jacobian and factorisation if `fresh`; None, or
        the message of a failed solve (e.g. MUMPS out of workspace: the Jacobian is then invalidated)."""
        if fresh:
            self._assemble_jacobian()
            self.ksp.setOperators(self.A)
            self.linear_solver.operator_changed()
        t0 = _time.perf_counter()
        self.linear_solver.solve(self.b, self.dx_vec, rtol)
        reason = self.ksp.getConvergedReason()
        if reason < 0:
            detail = self.linear_solver.failure_detail()
            self.invalidate_jacobian()
            return f"linear solve failed (PETSc KSP reason {reason}){detail}"
        if self.end_conditions:
            if fresh:
                self.end_conditions.factorised(lambda rhs, out: self.linear_solver.solve(rhs, out, rtol))
            self.end_conditions.correct(self.dx_vec)
        self.timings["factorise" if fresh else "solve"] += _time.perf_counter() - t0
        self.counters["factorisations" if fresh else "reused_solves"] += 1
        return None

    @property
    def field_increments(self) -> dict:
        """{field: (||dx_f||_inf, ||x_f||_inf)} of the last Newton update (partitioned: of the last sweep)."""
        return (self.partitioned or self.nonlinear_solver).field_increments

    def newton(self):
        """Solve R(x) = 0 for the current step (newton.Newton, or the partitioned sweeps of coupling_scheme
        "partitioned"). Returns (iterations, history of residual norms)."""
        self._reaction_ready = False
        fem_petsc.set_bc(self.x.vector, self.bcs)
        self.x.x.scatter_forward()
        self._guess = self.x.x.array.copy() if self.linearly_implicit is not None else None
        if self.partitioned is not None:
            return self.partitioned.solve()
        solve = lambda: self.nonlinear_solver.solve(self._assemble_residual, self._jacobian_current,  # noqa: E731
                                                    self._newton_correction)
        if self.linearly_implicit is not None and self._rate():
            try:
                with self.linearly_implicit.posed():
                    return self.linearly_implicit.solve()
            except NewtonDivergence as err:
                # the fallback: Newton on the full residual, from the state before the failed solve
                self.linearly_implicit.fallbacks += 1
                log.info("linearly implicit step failed (%s); solved by Newton", err)
                self.invalidate_jacobian()
                self.x.x.array[:] = self._guess
                self.x.x.scatter_forward()
        return solve()

    def pose_newton_system(self, dt):
        """The Newton system (A, b) of a step of dt from the current time at the current iterate, as
        `newton` assembles it (boundary values at the step's end, segregated mesh motion solved)."""
        self.set_bdf(dt)
        self.t.value = self.time + dt
        self.constraints.update(self.time + dt)
        if self.segregated:
            self.solve_mesh_motion()
        fem_petsc.set_bc(self.x.vector, self.bcs)
        self.x.x.scatter_forward()
        self._assemble_residual()
        self._assemble_jacobian()
        return self.A, self.b
