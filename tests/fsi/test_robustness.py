"""Robustness of the time integrator on the miniature tube (tests/helpers/engine_cases.py):
retries with dt halving, unrecoverable steps, ALE mesh inversion, checkpoint/resume, progress log."""
from __future__ import annotations

import logging
import math
import re

import numpy as np
import pytest

from helpers.engine_cases import QoIObserver, Quantities, field_errors, tube_problem
from ureterfsi.fsi import Observer, SolveFailure, SolverOptions, TimeIntegrator, TimeSettings
from ureterfsi.fsi.integrator import MeshInversion, StepFailure

DT = 0.005


class _Hook(Observer):
    """Calls action(problem) when the given step has been accepted (after the other observers)."""

    def __init__(self, step, action):
        self.step, self.action = step, action

    def observe(self, problem, step):
        if step == self.step:
            self.action(problem)


# ---------------------------------------------------------------------------------------------
# 1. retries with dt halving
def test_failed_step_is_retried_with_half_dt_and_dt_grows_back(caplog):
    """Ten times the nominal load, switched on in the first steps: with at most 3 Newton iterations
    the first step fails at dt = 0.01 s (its 3rd iterate reaches |R|/|R0| = 8e-8 > rtol), succeeds
    at dt/2 (4e-9), and later steps converge at the nominal dt again."""
    pb, case = tube_problem(options=SolverOptions(newton_max_iterations=3, newton_rtol=2e-8))
    case.amplitude.value = 3.0e4
    caplog.set_level(logging.INFO, logger="ureterfsi.fsi")
    integ = TimeIntegrator(pb, TimeSettings(end=0.04, dt=0.01, max_halvings=2))
    records = integ.run()
    dts = [r.dt for r in records]
    assert dts == pytest.approx([0.005, 0.005, 0.01, 0.01, 0.01], rel=1e-12)
    assert [r.step for r in records] == [1, 2, 3, 4, 5]
    assert pb.time == pytest.approx(0.04, rel=1e-12)
    assert all(r.newton_iterations <= 3 for r in records)
    retries = [m.getMessage() for m in caplog.records if "retrying with dt/2" in m.getMessage()]
    assert len(retries) == 1 and "step 1" in retries[0] and "dt=0.01 s" in retries[0]
    assert [(a.step, a.dt, a.halved) for a in integ.failed_attempts] == [(1, 0.01, True)]
    assert integ.failed_attempts[0].time == pytest.approx(0.01, rel=1e-12)


def test_unrecoverable_step_raises_solve_failure_with_time_step_and_history():
    """Two accepted steps, then Newton is limited to one iteration: the third step fails at dt and
    at dt/2 (max_halvings = 1); the SolveFailure names the time, the step and the residuals, and
    the problem is left at the last accepted state."""
    pb, case = tube_problem()

    def cripple(problem):
        problem.options.newton_max_iterations = 1

    integ = TimeIntegrator(pb, TimeSettings(end=0.05, dt=DT, max_halvings=1), [_Hook(2, cripple)])
    with pytest.raises(SolveFailure) as info:
        integ.run()
    msg = str(info.value)
    assert "step 3" in msg
    assert "t=0.01 s" in msg
    assert "after 1 halvings" in msg and "last dt=0.0025 s" in msg
    assert "no convergence in 1 Newton iterations" in msg
    history = re.search(r"residual history (.*)$", msg).group(1).split(", ")
    assert len(history) == 2 and all(math.isfinite(float(h)) and float(h) > 0 for h in history)
    assert pb.time == pytest.approx(0.01) and len(integ.records) == 2
    assert isinstance(info.value, StepFailure) and len(info.value.cause.history) == 2
    assert [(a.step, a.halved) for a in integ.failed_attempts] == [(3, True), (3, False)]
    assert [a.time for a in integ.failed_attempts] == pytest.approx([0.015, 0.0125], rel=1e-12)
    np.testing.assert_array_equal(pb.x.x.array, pb.x_n.x.array)


# ---------------------------------------------------------------------------------------------
# 2. ALE mesh inversion
def test_min_ale_jacobian_threshold_stops_the_run():
    """Deterministic trigger: the first step's minimum ALE Jacobian (0.99976) is below 0.9999."""
    pb, _ = tube_problem()
    with pytest.raises(SolveFailure) as info:
        TimeIntegrator(pb, TimeSettings(end=0.05, dt=DT, min_ale_jacobian=0.9999)).run()
    msg = str(info.value)
    assert "ALE mesh inverted at t=0.005 s (step 1)" in msg
    m = re.search(r"minimum Jacobian (\S+) <= 0.9999", msg)
    assert m and 0.999 < float(m.group(1)) < 0.9999
    assert isinstance(info.value, MeshInversion) and info.value.time == pytest.approx(0.005)
    assert info.value.min_jacobian == pytest.approx(float(m.group(1)), rel=1e-3)


def test_min_ale_jacobian_is_finite_on_the_axis():
    """Axisymmetric scene: the hoop stretch u_r / r is 0/0 at axis vertices; the minimum must still
    be a number (it was NaN, which silently disabled the inversion guard)."""
    pb, _ = tube_problem()
    assert pb.min_ale_jacobian() == 1.0
    pb.step(DT)
    j = pb.min_ale_jacobian()
    assert math.isfinite(j) and 0.999 < j < 1.0


def test_crushing_load_inverts_the_fluid_mesh():
    """A real inversion: a 300 kPa inward traction collapses the tube; Newton still converges on an
    inverted fluid mesh (after several retries), and the integrator stops with the minimum Jacobian."""
    pb, case = tube_problem()
    case.amplitude.value = -3.0e5
    with pytest.raises(SolveFailure) as info:
        TimeIntegrator(pb, TimeSettings(end=0.1, dt=0.01, max_halvings=3)).run()
    msg = str(info.value)
    m = re.search(r"ALE mesh inverted at t=(\S+) s \(step (\d+)\): minimum Jacobian (\S+) <= 0.0", msg)
    assert m, msg
    assert 0.0 < float(m.group(1)) < 0.1 and float(m.group(3)) <= 0.0
    # where: a vertex of the reference mesh, with the Jacobian the guard saw
    jmin, xyz = pb.min_ale_jacobian_at()
    assert jmin == pb.min_ale_jacobian() == info.value.min_jacobian
    X = pb.mesh.geometry.x
    assert np.min(np.linalg.norm(X - np.asarray(xyz), axis=1)) < 1e-12
    # the diagnosis names that vertex
    assert f"at the reference point ({', '.join(f'{c:.4g}' for c in xyz)}) m" in msg


# ---------------------------------------------------------------------------------------------
# 3. checkpoint / resume
class _Kill(Observer):
    def __init__(self, step=None):
        self.step = step

    def observe(self, problem, step):
        if step == self.step:
            raise KeyboardInterrupt(f"simulated kill after step {step}")


def _record_tuple(r):
    return (r.step, r.time, r.dt, r.newton_iterations, r.residual, r.min_ale_jacobian)


def _run(path, kill=None, end=0.06, **mesh_kw):
    pb, _ = tube_problem(**mesh_kw)
    obs = QoIObserver(Quantities(pb))
    settings = TimeSettings(end=end, dt=DT, checkpoint_interval=3, checkpoint_path=str(path))
    integ = TimeIntegrator(pb, settings, [obs, _Kill(kill)])
    return pb, obs, integ


def _rel(a, b):
    a, b = np.asarray(a, float), np.asarray(b, float)
    return float(np.abs(a - b).max() / max(np.abs(a).max(), 1e-300))


def test_checkpoint_resume_reproduces_the_uninterrupted_run(tmp_path):
    # uninterrupted reference (12 steps, checkpoints at 3, 6, 9, 12)
    ref_pb, ref_obs, ref = _run(tmp_path / "ref" / "ckpt.npz")
    ref.run()
    assert (tmp_path / "ref" / "ckpt.rank0of1.npz").exists()

    # killed after step 8: the last checkpoint is the one of step 6
    pb, obs, killed = _run(tmp_path / "run" / "ckpt.npz", kill=8)
    with pytest.raises(KeyboardInterrupt):
        killed.run()
    assert len(killed.records) == 8 and pb.time == pytest.approx(0.04)

    # fresh problem, same checkpoint path: resumes at step 6 and finishes
    pb, obs, resumed = _run(tmp_path / "run" / "ckpt.npz")
    records = resumed.run()
    assert resumed.records[0].step == 1 and len(records) == 12
    assert pb.time == pytest.approx(ref_pb.time, rel=1e-14)

    assert _rel(ref_pb.x.x.array, pb.x.x.array) < 1e-12
    assert _rel(ref_pb.x_nm1.x.array, pb.x_nm1.x.array) < 1e-12
    for key, series in ref_obs.records.items():
        assert len(obs.records[key]) == len(series) == 12, key
        assert _rel(series, obs.records[key]) < 1e-12, key
    for a, b in zip(ref.records, records):
        ta, tb = _record_tuple(a), _record_tuple(b)
        assert ta[:4] == tb[:4]
        assert _rel(ta[4:], tb[4:]) < 1e-12 or abs(ta[4] - tb[4]) < 1e-14


def test_a_killed_partitioned_solve_resumes_from_its_checkpoint(tmp_path):
    """The partitioned scheme keeps its blocks' LUs across steps; a resumed run starts without them, so it equals
    the uninterrupted run to the field tolerance (not bit for bit), having solved only the steps after the
    checkpoint."""
    def options():
        return SolverOptions(coupling_scheme="partitioned", newton_field_rtol=1e-6, reuse_jacobian=True)

    ref_pb, ref_obs, ref = _run(tmp_path / "ref" / "ckpt.npz", options=options())
    ref.run()
    pb, _, killed = _run(tmp_path / "run" / "ckpt.npz", kill=8, options=options())
    with pytest.raises(KeyboardInterrupt):
        killed.run()
    pb, obs, resumed = _run(tmp_path / "run" / "ckpt.npz", options=options())
    records = resumed.run()
    assert len(records) == 12 and pb.time == pytest.approx(ref_pb.time, rel=1e-14)
    # resumed at step 6: only the last 6 steps solved, with fresh blocks
    assert pb.counters["sweeps"] <= 0.6 * ref_pb.counters["sweeps"], (pb.counters, ref_pb.counters)
    assert max(field_errors(pb, ref_pb).values()) <= 1e-6
    for key, series in ref_obs.records.items():
        assert _rel(series[:6], obs.records[key][:6]) < 1e-12, key       # the checkpoint's own history
        assert _rel(series, obs.records[key]) < 1e-5, key


def test_the_forms_bdf_history_follows_every_change_of_the_history_or_the_step():
    """The forms read the history part of the BDF derivative, b1 x_n + b2 x_nm1, from one coefficient: it holds
    after a steady solve (0), after steps of changing dt (variable BDF2 weights), after a restored state and
    around the reaction's re-assembly (which swaps the step's own history in and out)."""
    pb, _ = tube_problem()

    def history_holds():
        b1, b2 = (float(c.value) for c in pb.bdf[1:])
        expected = b1 * pb.x_n.x.array + b2 * pb.x_nm1.x.array
        assert np.abs(pb.history.x.array - expected).max() <= 1e-14 * max(np.abs(expected).max(), 1.0)

    pb.solve_steady()
    history_holds()
    assert not pb.history.x.array.any()
    state = None
    for dt in (DT, DT, DT / 2):
        pb.step(dt)
        history_holds()
        state = state or pb.state()
    pb.set_state(state)
    history_holds()
    pb.assemble_reaction(pb.b.duplicate())
    history_holds()
    pb.step(DT)
    history_holds()


def test_checkpoint_of_a_different_problem_size_is_set_aside(tmp_path, caplog):
    pb, obs, integ = _run(tmp_path / "ckpt.npz", end=3 * DT)
    integ.run()
    pb, obs, other = _run(tmp_path / "ckpt.npz", end=6 * DT, n_axial=20)
    with caplog.at_level(logging.WARNING, logger="ureterfsi.fsi"):
        records = other.run()
    assert records[0].step == 1 and len(records) == 6
    assert re.search(r"not resumed, of another problem size .* set aside as ckpt\.rank0of1\.stale-\S+\.npz; "
                     r"starting from t = 0", caplog.text), caplog.text
    assert len(list(tmp_path.glob("ckpt.rank0of1.stale-*.npz"))) == 1


def test_checkpoint_of_another_identity_or_corrupt_is_set_aside(tmp_path, caplog):
    path = tmp_path / "ckpt.npz"
    pb, obs, integ = _run(path, end=3 * DT)
    integ.settings.identity = {"load.peak": "5e4", "mesh_sha256": "a" * 64}
    integ.run()
    pb, obs, other = _run(path, end=3 * DT)
    other.settings.identity = {"load.peak": "1e5", "mesh_sha256": "a" * 64}
    with caplog.at_level(logging.WARNING, logger="ureterfsi.fsi"):
        assert not other.has_checkpoint()
    assert "written by another run (load.peak 5e4 -> 1e5)" in caplog.text, caplog.text
    # truncated checkpoint: set aside, one line, restart from 0
    pb, obs, integ = _run(path, end=3 * DT)
    integ.run()
    f = tmp_path / "ckpt.rank0of1.npz"
    f.write_bytes(f.read_bytes()[:200])
    caplog.clear()
    pb, obs, again = _run(path, end=3 * DT)
    with caplog.at_level(logging.WARNING, logger="ureterfsi.fsi"):
        records = again.run()
    assert len(records) == 3 and records[0].step == 1
    assert "not resumed, unreadable (BadZipFile" in caplog.text, caplog.text
    assert len(list(tmp_path.glob("ckpt.rank0of1.stale-*.npz"))) == 2


# ---------------------------------------------------------------------------------------------
# 6. progress log
LOG_LINE = re.compile(
    r"step (?P<step>\d+) of ~(?P<total>\d+) \((?P<pct>\S+) %\)\s+ETA (?P<eta>unknown|\d+:\d\d:\d\d)\s+"
    r"t=(?P<t>\S+) s\s+dt=(?P<dt>\S+) s\s+newton=\s*(?P<its>\d+)\s+"
    r"residual=(?P<res>\S+) \(from (?P<res0>\S+)\)\s+min J_ale=(?P<jmin>\S+)\s+(?P<wall>\S+) s/step$")


def test_progress_log_line_per_step(caplog):
    pb, _ = tube_problem()
    caplog.set_level(logging.INFO, logger="ureterfsi.fsi")
    records = TimeIntegrator(pb, TimeSettings(end=4 * DT, dt=DT)).run()
    lines = [r.getMessage() for r in caplog.records
             if r.name == "ureterfsi.fsi" and r.getMessage().startswith("step ")]
    assert len(lines) == len(records) == 4
    for line, rec in zip(lines, records):
        m = LOG_LINE.match(line)
        assert m, line
        assert int(m["step"]) == rec.step
        assert float(m["t"]) == pytest.approx(rec.time, rel=1e-5)
        assert float(m["dt"]) == pytest.approx(rec.dt, rel=1e-3)
        assert int(m["its"]) == rec.newton_iterations
        assert float(m["res"]) == pytest.approx(rec.residual, rel=1e-3)
        assert float(m["res0"]) >= float(m["res"])
        jmin = float(m["jmin"])
        assert math.isfinite(jmin) and jmin == pytest.approx(rec.min_ale_jacobian, abs=1e-4)
        assert float(m["wall"]) >= 0.0
        assert int(m["total"]) == 4 and float(m["pct"]) == pytest.approx(100 * rec.time / (4 * DT), abs=0.05)
    assert LOG_LINE.match(lines[0])["eta"] == "unknown"        # the first step (compilation) is no rate
    assert LOG_LINE.match(lines[-1])["eta"] == "0:00:00"
