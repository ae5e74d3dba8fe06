"""The linearly implicit step of a fluid-alone problem (segregated mesh motion, SolverOptions.urine_step
"linearly_implicit"): BDF2 with the convecting velocity extrapolated from the two previous steps,

    rho J (dv/dt|_X + grad_x v^n+1 (c - w^n+1)) + ... = 0,   c = v^n + (dt/dt_prev)(v^n - v^n-1)   (v^n on the first),

the semi-implicit BDF/extrapolation scheme of Karniadakis, Israeli & Orszag (1991) in ALE form: the mesh velocity
w^n+1 is the BDF derivative of the prescribed mesh motion, known at the new time, so the residual is affine in the
step's unknowns (v, p) and one linear system per step replaces Newton's loop. The extrapolation error,
O(dt^2) in c, keeps the scheme second order (tests/fsi/test_linearly_implicit.py).

The system A dx = R(x_0) (x_0 the predictor, A the residual's derivative) is solved by GMRES, right-preconditioned
by the kept LU of an earlier step's A (the problem's linear solver), its products A y the assembled action of the
derivative on y (no matrix assembly): the GMRES residual is the true one, so the stop is Newton's residual test
||R|| <= max(newton_atol, newton_rtol ||R(x_0)||). The LU is refreshed at the next step when a solve needed more than
SolverOptions.krylov_refactorise_iterations iterations (a stale LU's extra iterations cost more than a
factorisation) or with an LU of another b0/dt (the first BDF2 step after Backward Euler's, a halved step: that
step is left to GMRES), or at once when GMRES fails within twice that. A step it cannot solve is
solved again by Newton on the full residual (the fallback, counted in `fallbacks`).
"""
from __future__ import annotations

import contextlib
import time

import numpy as np
import ufl
from dolfinx import fem
from dolfinx.fem import petsc as fem_petsc
from petsc4py import PETSc

from .newton import NewtonDivergence


class LinearlyImplicitStep:
    """The affine residual of a linearly implicit step of the problem `pb` (a MonolithicFSI) and its operator, with
    the residual's terms `terms(dx, convecting=...)` (forms.residual_terms on pb's measures)."""

    def __init__(self, pb, terms):
        if not pb.segregated:
            raise ValueError("urine_step 'linearly_implicit' linearises a fluid-alone step whose mesh motion is "
                             "prescribed: it needs mesh_motion_coupling 'segregated'")
        if pb.options.linear_solver == "fieldsplit":
            raise ValueError("urine_step 'linearly_implicit' preconditions its GMRES with the kept LU: it needs a direct "
                             "linear_solver (GMRES inside GMRES is not a fixed preconditioner)")
        self.pb = pb
        self.convecting_state = fem.Function(pb.W, name="convecting_state")
        whole = terms(pb.dx, convecting=pb.split(self.convecting_state)["velocity"])
        R = whole.urine + whole.solids + whole.loads
        self.residual_form = fem.form(R)
        J = ufl.derivative(R, pb.x)
        self.jacobian_form = fem.form(J)
        self.direction = fem.Function(pb.W, name="krylov_direction")
        self.action_form = fem.form(ufl.action(J, self.direction))
        self.fallbacks = 0
        pb.counters["krylov_iterations"] = 0
        n = pb.x.vector.getLocalSize()
        self.operator = PETSc.Mat().createPython(((n, None), (n, None)), _Action(self), comm=pb.comm)
        self.operator.setUp()
        self.ksp = ksp = PETSc.KSP().create(pb.comm)
        ksp.setOperators(self.operator)
        ksp.setType("gmres")
        # no restart within the iterations a solve may take (krylov_refactorise_iterations, twice): one vector each
        ksp.setGMRESRestart(max(2 * pb.options.krylov_refactorise_iterations, 1))
        ksp.setPCSide(PETSc.PC.Side.RIGHT)
        ksp.setNormType(PETSc.KSP.NormType.UNPRECONDITIONED)
        ksp.getPC().setType("python")
        ksp.getPC().setPythonContext(_KeptLU(pb))
        self.refresh = False

    def extrapolate(self, dt: float) -> None:
        """The convecting state of the step to t_n + dt: x_n + (dt/dt_prev)(x_n - x_n-1), or x_n on the first step."""
        pb = self.pb
        c = self.convecting_state.x.array
        c[:] = pb.x_n.x.array
        if pb.dt_prev:
            c += (dt / pb.dt_prev) * (pb.x_n.x.array - pb.x_nm1.x.array)

    @contextlib.contextmanager
    def posed(self):
        """The problem's residual and Jacobian forms are this step's affine ones inside the block."""
        pb = self.pb
        saved = pb.residual_form, pb.jacobian_form
        pb.residual_form, pb.jacobian_form = self.residual_form, self.jacobian_form
        try:
            yield
        finally:
            pb.residual_form, pb.jacobian_form = saved

    def solve(self) -> tuple[int, list]:
        """x = x_0 - A^-1 R(x_0) for the step posed in the problem (forms `posed`); (GMRES iterations, residual norms
        before and after). NewtonDivergence if GMRES fails with a fresh LU too."""
        pb, o = self.pb, self.pb.options
        r0 = pb._assemble_residual()
        history = [r0]
        if not np.isfinite(r0):
            raise NewtonDivergence("non-finite residual of the linearly implicit step", history)
        if r0 <= o.newton_atol:
            return 0, history
        cap = max(2 * o.krylov_refactorise_iterations, 1)
        x0 = pb.x.vector.copy()
        for fresh in (self.refresh or not pb.jacobian_kept(), True):
            if fresh:
                pb._assemble_jacobian()
                t0 = time.perf_counter()
                pb.ksp.setOperators(pb.A)
                pb.linear_solver.operator_changed()
                pb.ksp.setUp()
                pb.timings["factorise"] += time.perf_counter() - t0
                pb.counters["factorisations"] += 1
                self.refresh = False
            self.ksp.setTolerances(rtol=o.newton_rtol, atol=o.newton_atol, max_it=cap)
            t0 = time.perf_counter()
            self.ksp.solve(pb.b, pb.dx_vec)
            pb.timings["solve"] += time.perf_counter() - t0     # GMRES: its LU solves and action assemblies
            its = self.ksp.getIterationNumber()
            pb.counters["krylov_iterations"] += its
            if self.ksp.getConvergedReason() > 0:
                break
            if fresh:
                raise NewtonDivergence(f"GMRES with a fresh LU: no convergence in {cap} iterations "
                                       f"(KSP reason {self.ksp.getConvergedReason()})", history)
        pb.x.vector.waxpy(-1.0, pb.dx_vec, x0)
        pb.x.x.scatter_forward()
        history.append(pb._assemble_residual())    # the step's residual, kept for the reaction
        if not np.isfinite(history[-1]):
            raise NewtonDivergence("non-finite residual of the linearly implicit step", history)
        self.refresh = its > o.krylov_refactorise_iterations or not pb._jacobian_current()
        return its, history


class _Action:
    """PETSc Python matrix: y -> A y, the action of the affine residual's derivative (the columns and rows of the
    constrained dofs those of the identity, as the assembled Jacobian's with its boundary conditions)."""

    def __init__(self, step: LinearlyImplicitStep):
        self.step = step

    def mult(self, mat, y, out):
        step, pb = self.step, self.step.pb
        d = step.direction
        d.x.array[: y.getLocalSize()] = y.array_r
        d.x.scatter_forward()
        d.x.array[pb.constraints.constrained] = 0.0
        with out.localForm() as loc:
            loc.set(0.0)
        fem_petsc.assemble_vector(out, step.action_form)
        out.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
        owned = pb.constraints.constrained[pb.constraints.constrained < y.getLocalSize()]
        out.array_w[owned] = y.array_r[owned]


class _KeptLU:
    """PETSc Python preconditioner: one solve with the problem's kept LU (its linear solver)."""

    def __init__(self, pb):
        self.pb = pb

    def apply(self, pc, x, y):
        self.pb.linear_solver.solve(x, y, 0.0)
        self.pb.counters["reused_solves"] += 1
