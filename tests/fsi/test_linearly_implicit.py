"""The linearly implicit urine step (SolverOptions.urine_step "linearly_implicit", ureterfsi.fsi.linearly_implicit):
BDF2 with the convecting velocity extrapolated from the two previous steps, one linear system per step.

On the expanding tube of tests/helpers/fluid_tube.py (ALE, convection, backflow-stabilised open end):
- its temporal order against the time-continuous solution, represented by the fully implicit (Newton) BDF2 solution
  at a 32x shorter step: ~2 (the extrapolation's O(dt^2) error does not lower BDF2's order);
- it conserves mass as exactly as Newton's step (the continuity rows are linear either way);
- it is the scheme it claims: its step solves the affine residual with the extrapolated convecting velocity, which
  differs from Newton's converged step by O(dt^2) (a step whose convecting velocity were the previous state's would
  differ by O(dt) and fail the order test).
"""
import math

import numpy as np
import pytest

from ureterfsi.scenes import verification as V
from helpers.fluid_tube import L, R0, A, OMEGA, run

END = 0.032
TIGHT = dict(newton_atol=1e-16, newton_rtol=1e-13, reuse_jacobian=True, predictor="quadratic")


def final_state(n_steps, **options):
    """(velocity, pressure) at END after n_steps steps of the tube, and the problem."""
    _, vol, pb = run(END / n_steps, n_steps, "segregated", **(TIGHT | options))
    _, vd = pb.sub("velocity").collapse()
    _, pd = pb.sub("pressure").collapse()
    return pb.x.x.array[vd].copy(), pb.x.x.array[pd].copy(), vol, pb


@pytest.fixture(scope="module")
def reference():
    return final_state(256)


def test_linearly_implicit_step_is_second_order(reference):
    v_ref, p_ref, _, _ = reference
    steps = np.array([8, 16, 32])
    errors = {"velocity": [], "pressure": []}
    for n in steps:
        v, p, _, pb = final_state(n, urine_step="linearly_implicit")
        errors["velocity"].append(np.abs(v - v_ref).max() / np.abs(v_ref).max())
        errors["pressure"].append(np.abs(p - p_ref).max() / np.ptp(p_ref))
    print("linearly implicit errors", errors, pb.counters)
    for name, e in errors.items():
        orders = V.observed_order(END / steps, np.array(e))
        print(name, "observed orders", orders)
        assert np.all((orders > 1.8) & (orders < 2.3)), (name, orders)
    assert pb.linearly_implicit.fallbacks == 0


def test_linearly_implicit_step_matches_newton_and_conserves_mass(reference):
    """At dt = END/16 the two schemes' states differ by less than Newton's own time-discretisation error (both
    second order, the difference O(dt^2)); the fluid volume follows the prescribed wall to round-off."""
    v_ref, _, _, _ = reference
    v_n, p_n, _, _ = final_state(16)
    v_li, p_li, vol, _ = final_state(16, urine_step="linearly_implicit")
    newton_error = np.abs(v_n - v_ref).max() / np.abs(v_ref).max()
    difference = np.abs(v_li - v_n).max() / np.abs(v_n).max()
    print("Newton's error", newton_error, "linearly implicit - Newton", difference)
    assert difference < 3.0 * newton_error and difference < 2e-3
    t = END / 16 * np.arange(17)
    np.testing.assert_allclose(vol, math.pi * L * (R0 * (1 + A * np.sin(OMEGA * t))) ** 2, rtol=1e-10)


def test_linearly_implicit_needs_a_prescribed_mesh_motion():
    with pytest.raises(ValueError, match="segregated"):
        run(2e-3, 1, "monolithic", urine_step="linearly_implicit")
    with pytest.raises(ValueError, match="direct"):
        run(2e-3, 1, "segregated", urine_step="linearly_implicit", linear_solver="fieldsplit")
    with pytest.raises(ValueError, match="urine_step"):
        run(2e-3, 1, "segregated", urine_step="explicit")
