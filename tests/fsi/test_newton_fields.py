"""Newton's convergence test per field (SolverOptions.newton_field_rtol): one residual norm sums rows of
different scales (the Mooney-Rivlin wall's stiffness rows outweigh the urine's viscous rows), so a contracting
modified Newton meets the residual test with the velocity still off; the per-field increment test closes that.
Verified on the axisymmetric Mooney-Rivlin tube against a tightly converged full Newton."""
from __future__ import annotations

import numpy as np
import pytest

from helpers.engine_cases import field_errors, tube_problem, tube_reference, tube_run
from ureterfsi.fsi import NewtonDivergence, SolverOptions

CONFIG_TOL = dict(linear_solver="mumps", newton_rtol=1e-8, newton_atol=1e-10)


@pytest.fixture(scope="module")
def reference():
    with tube_reference() as pb:
        yield pb


@pytest.mark.parametrize("field_rtol", [1e-6, 1e-8])
def test_modified_newton_converges_every_field(reference, field_rtol):
    pb, its = tube_run(reuse_jacobian=True, newton_field_rtol=field_rtol, **CONFIG_TOL)
    errors = field_errors(pb, reference)
    assert max(errors.values()) <= field_rtol, errors
    assert pb.counters["factorisations"] <= 3, pb.counters     # still a modified Newton: the factor is kept


def test_the_residual_test_alone_leaves_the_velocity_off(reference):
    """The motivating case: at the same tolerances without the field test the velocity is > 1e-6 off (2.9e-6
    when measured) while the solid's displacement is converged to 1e-10."""
    pb, _ = tube_run(reuse_jacobian=True, **CONFIG_TOL)
    errors = field_errors(pb, reference)
    assert errors["velocity"] > 1e-6 and errors["displacement"] < 1e-8, errors


def test_a_step_that_does_not_converge_names_the_field():
    pb, _ = tube_problem(options=SolverOptions(reuse_jacobian=True, newton_field_rtol=1e-12,
                                               newton_max_iterations=3, **CONFIG_TOL))
    pb.solve_steady()
    with pytest.raises(NewtonDivergence, match=r"last increment relative to the field: velocity \d"):
        pb.step(2e-3)


def _checkpointed_and_not(tmp_path, **options):
    """The tube over 12 steps with checkpoints every 3 steps (each drops the kept factorisation, as a resumed
    run starts without one) and without: the same problem, different Jacobian histories."""
    from ureterfsi.fsi import TimeIntegrator, TimeSettings

    states = []
    for path in (tmp_path / f"ckpt{len(options)}.npz", None):
        pb, _ = tube_problem(options=SolverOptions(reuse_jacobian=True, **CONFIG_TOL, **options))
        settings = TimeSettings(end=0.024, dt=2e-3, checkpoint_interval=3 if path else 0,
                                checkpoint_path=str(path) if path else None)
        TimeIntegrator(pb, settings).run()
        states.append(pb)
    return states


def test_the_result_does_not_depend_on_the_jacobian_history(tmp_path):
    """With the field test a run with checkpoints equals one without to the field tolerance; with the residual
    test alone it did not (the default model 3 run after its first checkpoint: 1.5e-4 in the hole
    velocity, docs/performance.md)."""
    with_ckpt, without = _checkpointed_and_not(tmp_path, newton_field_rtol=1e-6)
    errors = field_errors(with_ckpt, without)
    assert max(errors.values()) <= 1e-6, errors
