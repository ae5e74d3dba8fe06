"""ureterfsi.fsi.newton on a toy system posed through its three callables: R_i(x) = x_i^3 - c_i (two "fields"),
J = diag(3 x^2). Quadratic convergence to c^(1/3), the Eisenstat-Walker forcing sequence, a failed linear solve,
a non-finite residual and the per-field increment test."""
from __future__ import annotations

import math

import numpy as np
import pytest
from dolfinx import fem
from dolfinx import mesh as dmesh
from mpi4py import MPI

from ureterfsi.fsi import NewtonDivergence, SolverOptions
from ureterfsi.fsi.newton import ETA_MAX, Newton, fields_off, measure_field_increments


class Toy:
    """x^3 = c on the owned dofs of P1 on a unit interval; field "a" the first half of them, "b" the rest."""

    def __init__(self, options, c_a=2.0, c_b=3.0, start=1.0):
        V = fem.FunctionSpace(dmesh.create_unit_interval(MPI.COMM_SELF, 7), ("Lagrange", 1))
        self.x = fem.Function(V)
        self.x.x.array[:] = start
        self.dx = self.x.vector.duplicate()
        self.b = self.x.vector.duplicate()
        n = V.dofmap.index_map.size_local
        self.c = np.where(np.arange(n) < n // 2, c_a, c_b)
        self.fields = {"a": np.arange(n // 2), "b": np.arange(n // 2, n)}
        self.newton = Newton(options, self.x, self.dx, self.fields, MPI.COMM_SELF)
        self.calls, self.jacobian = [], None

    def residual(self) -> float:
        self.b.array[:] = self.x.x.array ** 3 - self.c
        return self.b.norm()

    def correction(self, fresh: bool, rtol: float):
        self.calls.append((fresh, rtol))
        if fresh:
            self.jacobian = 3.0 * self.x.x.array ** 2
        self.dx.array[:] = self.b.array / self.jacobian
        return None

    def solve(self):
        return self.newton.solve(self.residual, lambda: self.jacobian is not None, self.correction)


def test_newton_converges_quadratically_to_the_root():
    toy = Toy(SolverOptions(newton_rtol=1e-14, newton_atol=1e-14))
    its, history = toy.solve()
    np.testing.assert_allclose(toy.x.x.array, np.cbrt(toy.c), rtol=1e-14)
    assert its == len(history) - 1 and history[-1] <= 1e-14 * history[0]
    # quadratic once close: r_k+1 <= 10 r_k^2 (the last residual is round-off)
    assert all(r1 <= 10.0 * r0 ** 2 for r0, r1 in zip(history[2:-2], history[3:-1]))
    assert all(fresh for fresh, _ in toy.calls)
    assert set(toy.newton.field_increments) == {"a", "b"}


def test_eisenstat_walker_forcing_sequence():
    """eta_0 = ETA_MAX; eta_k = min(ETA_MAX, max(0.9 (r_k / r_k-1)^2 [>= 0.9 eta_k-1^2 when that exceeds 0.1],
    0.5 max(atol, rtol r_0) / r_k, krylov_rtol))."""
    o = SolverOptions(krylov_forcing="eisenstat_walker", krylov_rtol=1e-9, newton_rtol=1e-12, newton_atol=1e-14)
    toy = Toy(o, start=0.2)
    _, history = toy.solve()
    target = max(o.newton_atol, o.newton_rtol * history[0])
    expected = []
    for k, r in enumerate(history[:len(toy.calls)]):
        eta = ETA_MAX
        if k > 0:
            eta = 0.9 * (r / history[k - 1]) ** 2
            if 0.9 * expected[-1] ** 2 > 0.1:
                eta = max(eta, 0.9 * expected[-1] ** 2)
        expected.append(min(ETA_MAX, max(eta, 0.5 * target / r, o.krylov_rtol)))
    assert [rtol for _, rtol in toy.calls] == expected
    assert len(set(expected)) > 1
    fixed = Toy(SolverOptions(krylov_rtol=1e-9))
    fixed.solve()
    assert {rtol for _, rtol in fixed.calls} == {1e-9}


def test_modified_newton_keeps_the_jacobian_while_it_contracts():
    toy = Toy(SolverOptions(reuse_jacobian=True, reuse_contraction=0.5, newton_rtol=1e-12, newton_atol=1e-14,
                            newton_max_iterations=40), start=1.4)
    toy.solve()
    np.testing.assert_allclose(toy.x.x.array, np.cbrt(toy.c), rtol=1e-11)
    fresh = [f for f, _ in toy.calls]
    assert fresh[0] and not all(fresh)


def test_a_residual_within_atol_keeps_the_factorisation():
    """Past ||R|| <= newton_atol only the increment test goes on, and the residual's ratio there (round-off on a real
    system) says nothing of the factorisation: a correction with half Newton's step contracts by 1/2, above
    reuse_contraction, so it is refactorised at every iteration until ||R|| <= atol and never after."""
    toy = Toy(SolverOptions(reuse_jacobian=True, reuse_contraction=0.4, newton_rtol=1e-30, newton_atol=1e-6,
                            newton_field_rtol=1e-12, newton_max_iterations=80), start=1.4)

    def half_step(fresh, rtol):
        toy.calls.append((fresh, rtol))
        if fresh:
            toy.jacobian = 6.0 * toy.x.x.array ** 2
        toy.dx.array[:] = toy.b.array / toy.jacobian

    toy.correction = half_step
    _, history = toy.solve()
    np.testing.assert_allclose(toy.x.x.array, np.cbrt(toy.c), rtol=1e-9)   # its increments within 1e-10
    fresh = [f for f, _ in toy.calls]
    first = next(k for k, r in enumerate(history) if r <= 1e-6)
    assert 5 < first < len(fresh) - 5
    assert all(fresh[1:first]) and not any(fresh[first:])


def test_failures_raise_newton_divergence_with_the_history():
    toy = Toy(SolverOptions())
    toy.correction = lambda fresh, rtol: "linear solve failed (a reason)"
    with pytest.raises(NewtonDivergence, match=r"^linear solve failed \(a reason\)$") as err:
        toy.solve()
    assert len(err.value.history) == 1
    toy = Toy(SolverOptions(), start=math.nan)
    with pytest.raises(NewtonDivergence, match="non-finite residual at Newton iteration 0"):
        toy.solve()
    toy = Toy(SolverOptions(newton_max_iterations=2, newton_rtol=1e-14, newton_atol=1e-14, newton_field_rtol=1e-14),
              start=5.0)
    with pytest.raises(NewtonDivergence, match=r"no convergence in 2 Newton iterations \(last increment relative to "
                                               r"the field: a \d.*, b \d") as err:
        toy.solve()
    assert len(err.value.history) == 3


def test_fields_off_and_the_increments():
    assert fields_off({}, ["a", "b"], None, 0.0) == {}
    assert fields_off({}, ["a", "b"], 1e-8, 0.0) == {"a": math.inf, "b": math.inf}
    inc = {"a": (1e-3, 1.0), "b": (1e-12, 1e-2), "c": (1e-9, 0.0)}
    assert fields_off(inc, inc, 1e-8, 1e-10) == {"a": 1e-3, "c": 1e-9 / 1e-300}
    dx, x = np.array([1.0, -4.0, 0.5]), np.array([-2.0, 1.0, 3.0])
    assert measure_field_increments(dx, x, {"a": [0, 1], "b": [2]}, MPI.COMM_SELF) == {"a": (4.0, 2.0), "b": (0.5, 3.0)}
