"""Newton's method for one time step's R(x) = 0: x_k+1 = x_k - dx_k, J(x_k) dx_k = R(x_k), with its convergence
tests (residual and per-field increment), modified Newton (a kept factorisation while ||R_k|| contracts) and the
Eisenstat-Walker forcing of inexact linear solves.

The problem poses the system (MonolithicFSI): it assembles the residual and solves the linearised system; this
module decides when to refresh the Jacobian, how accurately to solve, when to stop and what to report.
"""
from __future__ import annotations

import math
from typing import Callable

import numpy as np
from mpi4py import MPI

# largest Eisenstat-Walker forcing term: the momentum rows dominate the residual norm, and a looser solve leaves
# the kinematic rows' velocity off by more than the LU path's (docs/performance.md)
ETA_MAX = 1e-3


class NewtonDivergence(RuntimeError):
    """Newton failed to converge (or produced a non-finite residual) in one step."""

    def __init__(self, message, history):
        super().__init__(message)
        self.history = history


def measure_field_increments(dx: np.ndarray, x: np.ndarray, field_dofs: dict, comm) -> dict:
    """{field: (||dx_f||_inf, ||x_f||_inf)} of the update dx of the state x over each field's owned local dofs
    `field_dofs` (reduced over ranks)."""
    local = np.array([[np.abs(a[d]).max(initial=0.0) for d in field_dofs.values()] for a in (dx, x)])
    reduced = np.empty_like(local)
    comm.Allreduce(local, reduced, op=MPI.MAX)
    inc, scale = reduced
    return {f: (i, s) for f, i, s in zip(field_dofs, inc.tolist(), scale.tolist())}


def fields_off(increments: dict, fields, rtol: float | None, floor: float) -> dict:
    """{field: ||dx_f|| / ||x_f||} of the fields whose last increment exceeds max(rtol ||x_f||, floor) (every one of
    `fields`, as inf, before the first update); {} when rtol is None (no field test)."""
    if rtol is None:
        return {}
    if not increments:
        return dict.fromkeys(fields, math.inf)
    return {f: i / max(s, 1e-300) for f, (i, s) in increments.items() if i > max(rtol * s, floor)}


class Newton:
    """Newton's iteration on the state `x` (a dolfinx Function) with the update vector `dx` (PETSc Vec), the
    tolerances and strategies of `options` (SolverOptions: newton_*, reuse_jacobian, reuse_contraction,
    krylov_forcing, krylov_rtol). `field_dofs` {field: owned local dofs} defines the per-field increment tests."""

    def __init__(self, options, x, dx, field_dofs: dict, comm):
        self.options = options
        self.x, self.dx = x, dx
        self.field_dofs = field_dofs
        self.comm = comm
        self.field_increments = {}      # {field: (||dx_f||_inf, ||x_f||_inf)} of the last update
        self._eta = ETA_MAX            # the last forcing term (set anew at each step's first iteration)

    def _forcing(self, history, r0) -> float:
        """Relative tolerance of the next linear solve. "eisenstat_walker" (Eisenstat & Walker 1996, choice 2,
        gamma = 0.9, alpha = 2, with their safeguard): eta_k = 0.9 (r_k / r_k-1)^2, at least 0.9 eta_k-1^2 when
        that exceeds 0.1; at most ETA_MAX (ETA_MAX at a step's first iteration), and no smaller than needed to
        reach Newton's tolerance from r_k (0.5 tol / r_k) nor than krylov_rtol."""
        o = self.options
        if o.krylov_forcing == "fixed":
            return o.krylov_rtol
        eta = ETA_MAX
        if len(history) > 1:
            eta = 0.9 * (history[-1] / history[-2]) ** 2
            if 0.9 * self._eta ** 2 > 0.1:
                eta = max(eta, 0.9 * self._eta ** 2)
        target = max(o.newton_atol, o.newton_rtol * r0)
        self._eta = min(ETA_MAX, max(eta, 0.5 * target / history[-1], o.krylov_rtol))
        return self._eta

    def _fields_off(self, rtol: float | None) -> dict:
        """fields_off of the last update under rtol and the absolute SolverOptions.newton_increment_floor."""
        return fields_off(self.field_increments, self.field_dofs, rtol, self.options.newton_increment_floor)

    def solve(self, residual: Callable[[], float], jacobian_current: Callable[[], bool],
              correction: Callable[[bool, float], str | None]) -> tuple[int, list]:
        """Solve R(x) = 0 from the current x; returns (iterations, history of residual norms ||R_k||).

        residual() assembles R(x) and returns its norm; jacobian_current() says whether the kept factorisation is
        of this step's operator; correction(fresh, rtol) solves J dx = R to relative tolerance rtol, with a fresh
        Jacobian and factorisation if `fresh`, and returns None or the failure's message.

        Converged: ||R_k|| <= newton_atol or ||R_k|| <= newton_rtol ||R_0|| (k > 0), and every field's last
        increment within newton_field_rtol; stagnated (accepted): every field's increment within newton_stol.
        A Jacobian is kept (reuse_jacobian) while ||R_k|| / ||R_k-1|| < reuse_contraction or ||R_k|| <= newton_atol.
        Failure: NewtonDivergence with the history."""
        o = self.options
        x, dx = self.x, self.dx
        history = []
        r0 = None
        self.field_increments = {}
        for it in range(o.newton_max_iterations + 1):
            r = residual()
            history.append(r)
            if not math.isfinite(r):
                raise NewtonDivergence(f"non-finite residual at Newton iteration {it}", history)
            r0 = r if r0 is None else r0
            small = r <= o.newton_atol or (it > 0 and r <= o.newton_rtol * r0)
            if small and (it == 0 or not self._fields_off(o.newton_field_rtol)):
                return it, history
            if it == o.newton_max_iterations:
                break
            contraction = history[-1] / history[-2] if len(history) > 1 else 0.0
            # a residual within newton_atol is round-off: its ratio says nothing of the kept factorisation
            contracts = contraction < o.reuse_contraction or history[-1] <= o.newton_atol
            fresh = not (o.reuse_jacobian and jacobian_current() and contracts)
            failure = correction(fresh, self._forcing(history, r0))
            if failure is not None:
                raise NewtonDivergence(failure, history)
            x.vector.axpy(-1.0, dx)
            x.x.scatter_forward()
            self.field_increments = measure_field_increments(dx.array_r, x.x.array, self.field_dofs, self.comm)
            if not self._fields_off(o.newton_stol):
                r = residual()
                history.append(r)
                if math.isfinite(r):
                    return it + 1, history
        off = ", ".join(f"{f} {r:.1e}" for f, r in self._fields_off(o.newton_field_rtol).items())
        raise NewtonDivergence(f"no convergence in {o.newton_max_iterations} Newton iterations"
                               + (f" (last increment relative to the field: {off})" if off else ""), history)
