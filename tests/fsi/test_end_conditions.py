"""Lumped end conditions (fsi.end_conditions) on a rigid axisymmetric pipe (scenes.rigid_pipe) against exact
solutions and conservation: the 0D pelvis's exponential relaxation (time constant R C, R the pipe's Poiseuille
resistance), the mass balance of production, outflow and storage, the reflux volume of a voiding pressure step
(and its split by the scene's flux_split), Newton's convergence with the Jacobian's rank-k term, the valve's law and
the checkpoint of the 0D state; the partitioned sweeps (fsi.partitioned) with the same conditions against Newton on an
elastic tube (the rigid pipe has no wall to partition)."""
import math

import numpy as np
import pytest
from dolfinx import fem
from scipy.optimize import brentq

from ureterfsi.config.end_pressures import bladder_pressure
from ureterfsi.fsi import Compartment, MonolithicFSI, OpenBoundary, SolverOptions, Valve, Waveform
from ureterfsi.fsi.end_conditions import EndConditions
from ureterfsi.fsi.probes import assemble_scalar, flux_volume_forms
from ureterfsi.scenes.rigid_pipe import INLET, OUTLET, RigidPipe, rigid_pipe_scene
from ureterfsi.study.end_probes import EndProbes

TIGHT = SolverOptions(newton_rtol=1e-11, newton_atol=1e-13)
PIPE = RigidPipe()
R = PIPE.resistance
TAU = 0.1                    # s, the relaxation time R C posed
P0 = 100.0                   # Pa


def pelvis_problem(production=0.0, outlet=None, options=TIGHT):
    pelvis = OpenBoundary([INLET], backflow=0.0, condition=Compartment(TAU / R, lambda t: production, P0))
    """The pipe at rest, the pelvis at P0 (the flow develops within the first step: its viscous time is 1 us)."""
    pb = MonolithicFSI(rigid_pipe_scene(PIPE, 4, pelvis, outlet or OpenBoundary([OUTLET], 0.0, backflow=0.0)), options)
    pb.fill("pressure", P0)
    return pb


def relaxation_error(dt, end=0.2):
    """max over the steps of |p / p_exact - 1|, p_exact = P0 exp(-t / (R C)); Newton iterations per step."""
    pb = pelvis_problem()
    errors, iterations = [], []
    while pb.time < end - 1e-12:
        its, _ = pb.step(dt)
        iterations.append(its)
        errors.append(abs(pb.end_conditions.p[0] / (P0 * math.exp(-pb.time / TAU)) - 1.0))
    return max(errors), iterations


def test_pelvis_relaxation_against_exact_exponential():
    """C dp/dt = -Q, Q = p / R: p = P0 exp(-t / (R C)); BDF2 (Backward Euler first step) converges at order 2, and
    the problem is linear, so the exact Jacobian (Woodbury term) gives one Newton iteration per step."""
    rows = [(dt, *relaxation_error(dt)) for dt in (0.01, 0.005, 0.0025)]
    orders = [math.log(rows[i][1] / rows[i + 1][1]) / math.log(2.0) for i in range(len(rows) - 1)]
    print("\n[0D pelvis on a rigid pipe, tau = R C = 0.1 s]  dt   max|p/p_exact - 1|  order  Newton its")
    for i, (dt, err, its) in enumerate(rows):
        print(f"    {dt:.4f}  {err:.3e}  {orders[i - 1] if i else float('nan'):5.2f}  {max(its)}")
    assert rows[-1][1] < 1e-3
    assert min(orders) > 1.8
    assert all(max(its) == 1 for _, _, its in rows)


def test_newton_needs_the_rank_k_term(monkeypatch):
    """Without the Woodbury correction the 0D coupling is a fixed point (the factor dt/(R C) per iteration): more
    Newton iterations; with it, one (test above). Guards the Jacobian term, which leaves the solution unchanged."""
    monkeypatch.setattr(EndConditions, "correct", lambda self, dx: None)
    _, iterations = relaxation_error(0.01, end=0.03)
    assert max(iterations) >= 3


def test_mass_balance_production_outflow_storage():
    """Production = outflow + pelvis storage + change of the lumen volume (rigid: 0), every step, to the solver's
    tolerance; the outflow through a one-way valve (forward resistance), fluxes from forms of their own."""
    production = 2.0e-9
    valve = OpenBoundary([OUTLET], backflow=0.0, condition=Valve(lambda t: 0.0, R, 1e3 * R, 1.0))
    pb = pelvis_problem(production, valve)
    forms = {k: fem.form(f) for k, f in flux_volume_forms(pb, INLET, OUTLET).items()}
    p_hist = [pb.end_conditions.p[0]] * 2
    worst, volume0 = 0.0, assemble_scalar(forms["fluid_volume"], pb.comm)
    for _ in range(6):
        pb.step(0.01)
        b0, b1, b2 = (float(c.value) for c in pb.bdf)
        p = pb.end_conditions.p[0]
        storage = (TAU / R) * (b0 * p + b1 * p_hist[-1] + b2 * p_hist[-2]) / 0.01
        p_hist.append(p)
        outflow = assemble_scalar(forms["outlet_flux"], pb.comm)
        inflow = assemble_scalar(forms["inlet_flux"], pb.comm)
        dV = assemble_scalar(forms["fluid_volume"], pb.comm) - volume0
        worst = max(worst, abs(production - outflow - storage) / production, abs(inflow - outflow) / production)
        assert dV == pytest.approx(0.0, abs=1e-18)
    print(f"\n[mass balance] max |production - outflow - storage| / production = {worst:.2e}")
    assert worst < 1e-8


def test_voiding_reflux_volume_against_poiseuille():
    """A bladder pressure step dp(t) (half-cosine rise, hold, release) through an open (stented) junction against the
    kidney at p_ref: quasi-steady Poiseuille backflow Q = dp / R, reflux volume int dp dt / R."""
    ends = {"bladder": {"condition": "voiding", "filling_pressure": 0.0, "detrusor_pressure": 50.0,
                        "voiding_start": 0.0, "voiding_rise": 0.02, "voiding_hold": 0.04, "voiding_release": 0.02}}
    from dataclasses import replace

    import ufl
    p_b = bladder_pressure(ends, 0.0)
    scene = rigid_pipe_scene(PIPE, 4, OpenBoundary([INLET], 0.0, backflow=0.0),
                             OpenBoundary([OUTLET], backflow=0.0, condition=Waveform(p_b)))
    r = ufl.SpatialCoordinate(scene.mesh)[0]      # a "lumen" r < a/2 (a mesh line): 7/16 of Poiseuille's flux
    pb = MonolithicFSI(replace(scene, flux_split=ufl.conditional(ufl.lt(r, 0.5 * PIPE.radius), 1.0, 0.0)), TIGHT)
    pb.solve_steady()
    probes = EndProbes(pb, INLET, OUTLET, 1.0)
    probes.observe(pb, 0)
    dt = 0.0025
    while pb.time < 0.1 - 1e-12:
        pb.step(dt)
        probes.observe(pb, 0)
    exact = 50.0 * (0.02 / 2 + 0.04 + 0.02 / 2) / R
    lumen, annulus = probes.series["stent_lumen_reflux_volume"][-1], probes.series["annulus_reflux_volume"][-1]
    got = lumen + annulus
    print(f"\n[voiding reflux, rigid pipe] {got:.6e} m^3 vs Poiseuille {exact:.6e} m^3: {got / exact - 1:+.2e}; "
          f"r < a/2 share {lumen / got:.6f} vs 7/16; "
          f"bladder pressure peak {max(probes.series['bladder_pressure']):.1f} Pa")
    assert got == pytest.approx(exact, rel=2e-3)
    assert lumen / got == pytest.approx(7.0 / 16.0, rel=1e-6)
    # the kidney face's flux is the engine's one (its FaceFlux), the lumen part the scene's flux_split
    assert probes.inlet is pb.end_conditions.face_flux([INLET]) and probes.inlet.part_form is not None


def test_valve_law_and_quadratic_newton():
    """Steady flow through the pipe into a one-way valve to p_down: R Q + dp_valve(Q) = p_in - p_down, solved for Q
    exactly (forward: ~ dp / (R + R_f), backward: ~ -dp / (R + R_b)); in the valve's switch (a 50 Pa wide one, 10 Pa
    driving) Newton converges quadratically: log r_k+1 / log r_k >= 1.8 (r relative to r_0) once r_k < 1e-2."""
    rb = 1e3 * R
    for p_in, p_down, width in ((P0, 0.0, 1e-3), (0.0, P0, 1e-3), (10.0, 0.0, 50.0)):
        valve = Valve(lambda t, p=p_down: p, R, rb, width)
        scene = rigid_pipe_scene(PIPE, 4, OpenBoundary([INLET], p_in, backflow=0.0),
                                 OpenBoundary([OUTLET], backflow=0.0, condition=valve))
        pb = MonolithicFSI(scene, TIGHT)
        its, history = pb.solve_steady()
        q = pb.end_conditions.q[0]
        exact = brentq(lambda x: R * x + valve.pressure_drop(x)[0] - (p_in - p_down), -1.0, 1.0, xtol=1e-30, rtol=1e-14)
        rel = [r / history[0] for r in history]
        rates = [math.log(rel[k + 1]) / math.log(rel[k]) for k in range(len(rel) - 1)
                 if rel[k] < 1e-2 and rel[k + 1] > 1e-12]   # above the rounding floor
        print(f"\n[valve] dp = {p_in - p_down:+.0f} Pa, switch {width:g} Pa: Q = {q:.6e} vs {exact:.6e} m^3/s, "
              f"residuals {' '.join(f'{r:.1e}' for r in history)}")
        assert q == pytest.approx(exact, rel=1e-6)
        assert its <= 8
        assert all(r >= 1.8 for r in rates)


def test_kept_factorisation_takes_the_valves_current_slope():
    """With a kept factorisation (reuse_jacobian) the Woodbury term uses the valve's slope dp/dQ of the current
    iterate (Z = A^-1 a does not depend on it): inside the valve's switch (10 Pa driving, a 50 Pa wide switch, the
    slope from (R_f + R_b)/2 at Q = 0 to ~R_f) Newton stays quadratic on one factorisation. With the slope of the
    factorisation it converged linearly: 8 iterations and 2 factorisations."""
    from dataclasses import replace
    valve = Valve(lambda t: 0.0, R, 1e3 * R, 50.0)
    scene = rigid_pipe_scene(PIPE, 4, OpenBoundary([INLET], 10.0, backflow=0.0),
                             OpenBoundary([OUTLET], backflow=0.0, condition=valve))
    pb = MonolithicFSI(scene, replace(TIGHT, reuse_jacobian=True))
    its, history = pb.solve_steady()
    rel = [r / history[0] for r in history]
    rates = [math.log(rel[k + 1]) / math.log(rel[k]) for k in range(len(rel) - 1)
             if rel[k] < 0.2 and rel[k + 1] > 1e-12]
    print(f"\n[valve switch, kept LU] {its} iterations, {dict(pb.counters)}, residuals "
          f"{' '.join(f'{r:.1e}' for r in history)}")
    assert pb.counters["factorisations"] == 1 and its <= 5
    assert rates and all(r >= 1.8 for r in rates)


def test_steady_state_drains_the_production():
    """A steady solve poses C dp/dt = 0: the pelvis drains its production, Q_in = Q_prod, at p = R Q_prod."""
    production = 2.0e-9
    pb = pelvis_problem(production)
    pb.solve_steady()
    assert -pb.end_conditions.q[0] == pytest.approx(production, rel=1e-9)
    assert pb.end_conditions.p[0] == pytest.approx(R * production, rel=1e-6)


def test_checkpointed_end_state_restores_the_run():
    """state()/set_state() carry the 0D history: a restored run repeats the pressures of the uninterrupted one."""
    pb = pelvis_problem(production=1e-9)
    for _ in range(2):
        pb.step(0.01)
    saved = pb.state()
    run = [pb.step(0.01) and pb.end_conditions.p[0] for _ in range(2)]
    pb.set_state(saved)
    again = [pb.step(0.01) and pb.end_conditions.p[0] for _ in range(2)]
    assert np.allclose(run, again, rtol=1e-12)
    assert saved["end_conditions"]["p_n"] != pb.end_conditions.state()["p_n"]


TUBE_R = 3.5e7             # Pa s/m^3, ~ the test tube's Poiseuille resistance 8 mu L / (pi R_i^4)
SWEEPS = dict(linear_solver="mumps", newton_rtol=1e-8, newton_atol=1e-10, reuse_jacobian=True,
              coupling_scheme="partitioned", newton_field_rtol=1e-8)
EXACT = dict(linear_solver="mumps", reuse_jacobian=False, newton_rtol=1e-12, newton_atol=1e-20, newton_stol=1e-13,
             newton_max_iterations=40)
PRODUCTION = 2.0e-8         # m^3/s


def tube_with_ends(outlet: str, **options):
    """The elastic test tube (tests/helpers/engine_cases) between a pelvis (R C = 0.01 s, filled at PRODUCTION) and a
    bladder whose pressure oscillates (50 Pa at 32 Hz): at its face (`outlet` "waveform") or through a valve."""
    from helpers.engine_cases import INLET as TUBE_INLET, OUTLET as TUBE_OUTLET, tube_case
    bladder = lambda t: 50.0 * math.sin(200.0 * t)      # noqa: E731
    case = tube_case()
    case.scene.open_boundaries = [
        OpenBoundary([TUBE_INLET], 0.0, condition=Compartment(0.01 / TUBE_R, lambda t: PRODUCTION, 100.0)),
        OpenBoundary([TUBE_OUTLET], 0.0, condition=Waveform(bladder) if outlet == "waveform"
                     else Valve(bladder, TUBE_R, 1e3 * TUBE_R, 1.0))]
    return MonolithicFSI(case.scene, SolverOptions(**options))


def tube_ends_run(outlet, steps=4, **options):
    pb = tube_with_ends(outlet, **options)
    pb.solve_steady()
    return pb, [pb.step(2e-3)[0] for _ in range(steps)]


@pytest.mark.parametrize("outlet", ["waveform", "valve"])
def test_partitioned_sweeps_reach_the_monolithic_solution_with_lumped_ends(outlet):
    """The sweeps carry the face pressures of the current iterate and the rank-k term on the flow block's LU: their
    fixed point is Newton's, to the sweeps' tolerance (every field, the pelvic and bladder pressures and the end
    fluxes within newton_field_rtol = 1e-8), in as many sweeps per step as with open ends (test_partitioned: <= 8)."""
    from helpers.engine_cases import field_errors
    exact, _ = tube_ends_run(outlet, **EXACT)
    pb, sweeps = tube_ends_run(outlet, **SWEEPS)
    errors = field_errors(pb, exact)
    a, b = pb.end_conditions, exact.end_conditions
    ends = {"p": np.abs(a.p - b.p).max() / np.abs(b.p).max(), "Q": np.abs(a.q - b.q).max() / np.abs(b.q).max()}
    print(f"\n[partitioned, pelvis + bladder {outlet}] sweeps {sweeps}, flow LUs "
          f"{pb.counters['flow_factorisations']}; fields vs Newton "
          f"{' '.join(f'{f} {e:.1e}' for f, e in errors.items())}; end pressures {ends['p']:.1e}, "
          f"fluxes {ends['Q']:.1e}")
    assert max(errors.values()) <= 1e-8 and max(ends.values()) <= 1e-8, (errors, ends)
    assert max(sweeps) <= 8, sweeps


def test_partitioned_sweeps_need_the_flow_blocks_rank_k_term(monkeypatch):
    """Without the Woodbury term on the flow block's LU the compartment's steady pseudo-step (dp/dQ = 1e3 s / C, 1e5
    times the tube's resistance) is a diverging fixed point of the flow block's iteration."""
    from ureterfsi.fsi import NewtonDivergence
    monkeypatch.setattr(EndConditions, "correct", lambda self, dx: None)
    with pytest.raises(NewtonDivergence):
        tube_with_ends("valve", **SWEEPS).solve_steady()


def test_partitioned_mass_balance_with_a_moving_wall():
    """The partitioned sweeps keep the moving wall's balance (test_mass_balance_with_a_moving_wall): production =
    outflow + pelvis storage + S and Q_in - Q_out = S every step, to the sweeps' tolerance."""
    rows = moving_wall_pelvis_run(0.005, end=0.02, options=SolverOptions(**SWEEPS))
    scale = np.abs(rows[:, 1]).max()
    closure = np.abs(rows[:, 0] - rows[:, 1]).max() / scale
    flux_closure = np.abs(rows[:, 3] - rows[:, 1]).max() / scale
    print(f"\n[partitioned, moving wall + pelvis] max |production - storage - Q_out - S| / max|S| = {closure:.1e}; "
          f"|Q_in - Q_out - S| = {flux_closure:.1e}")
    assert closure < 1e-8 and flux_closure < 1e-8


def test_partitioned_steady_state_drains_the_production_and_restores_its_checkpoint():
    """Partitioned, on the elastic tube: the steady state drains the pelvis's production through the tube (Q_in =
    Q_out = Q_prod); state()/set_state() carry the 0D history, a restored run repeats the pressures to the sweeps'
    tolerance (the kept LUs and mixing differ, the fixed point does not)."""
    pb = tube_with_ends("valve", **SWEEPS)
    pb.solve_steady()
    q_in, q_out = pb.end_conditions.q
    assert -q_in == pytest.approx(PRODUCTION, rel=1e-8) and q_out == pytest.approx(PRODUCTION, rel=1e-8)
    pb.step(2e-3)
    saved = pb.state()
    run = [pb.step(2e-3) and pb.end_conditions.p.copy() for _ in range(2)]
    pb.set_state(saved)
    again = [pb.step(2e-3) and pb.end_conditions.p.copy() for _ in range(2)]
    assert np.allclose(run, again, rtol=1e-8, atol=0.0)


@pytest.mark.parametrize("change, key, text", [
    ({"bladder": {"junction_backward_resistance": 1.0e+7}}, "ends.bladder.junction_backward_resistance",
     "resists backflow more"),
    ({"kidney": {"urine_production": 1.0e-3}}, "ends.kidney.urine_production", "0.5-2 mL/min"),
])
def test_end_conditions_refused_in_one_line(change, key, text):
    """A valve resisting forward flow more than backflow, an implausible urine production: one line naming the
    key. (Voiding on a one-way study is posed: its wall takes the urine pressure, tests/study/test_one_way_wall_pressure.py.)"""
    from ureterfsi.config import ConfigError, deep_merge, load_config
    cfg = load_config()
    cfg["ends"] = deep_merge(cfg["ends"], change)
    with pytest.raises(ConfigError) as err:
        load_config(cfg)
    assert err.value.key == key and text in str(err.value) and "\n" not in str(err.value)


def moving_wall_pelvis_run(dt, end=0.04, options=TIGHT):
    """The engine's r-z tube (tests/helpers/engine_cases: a Mooney-Rivlin wall under a travelling load, fully coupled)
    with a pelvis at its inlet (production 5e-8 m^3/s into C = 1e-11 m^3/Pa) and the outlet open: per step
    (production - C dp/dt - Q_out, S, the BDF derivative of V = int J dX, Q_in - Q_out, the engine's recorded
    kidney-face flux (FaceFlux, w of the current iterate) minus the probes' (w the step's x_dot))."""
    from dataclasses import replace

    from helpers.engine_cases import INLET as T_IN, OUTLET as T_OUT, REFERENCE_STRESS, tube_case
    production, compliance = 5.0e-8, 1.0e-11
    case = tube_case(n_axial=20)
    ends = [OpenBoundary([T_IN], REFERENCE_STRESS, condition=Compartment(compliance, lambda t: production,
                                                                        REFERENCE_STRESS)),
            OpenBoundary([T_OUT], REFERENCE_STRESS)]
    pb = MonolithicFSI(replace(case.scene, open_boundaries=ends), options)
    pb.solve_steady()
    forms = {k: fem.form(f) for k, f in flux_volume_forms(pb, T_IN, T_OUT).items()}
    p, vol, rows = [pb.end_conditions.p[0]] * 2, [assemble_scalar(forms["fluid_volume"], pb.comm)] * 2, []
    while pb.time < end - 1e-12:
        pb.step(dt)
        b0, b1, b2 = (float(c.value) for c in pb.bdf)
        val = {k: assemble_scalar(f, pb.comm) for k, f in forms.items()}
        storage = compliance * (b0 * pb.end_conditions.p[0] + b1 * p[-1] + b2 * p[-2]) / dt
        dvdt = (b0 * val["fluid_volume"] + b1 * vol[-1] + b2 * vol[-2]) / dt
        rows.append((production - storage - val["outlet_flux"], val["fluid_volume_rate"], dvdt,
                     val["inlet_flux"] - val["outlet_flux"], pb.end_conditions.face_flux([T_IN]).recorded[0]
                     + val["inlet_flux"]))
        p.append(pb.end_conditions.p[0])
        vol.append(val["fluid_volume"])
    return np.array(rows)


def gcl_volume_error(rows, dt):
    """V(t) - V(0) - the BDF-integrated S at the last step: the BDF integral of dV/dt_BDF - S (Backward Euler first)."""
    e = [0.0, 0.0]
    for n, d in enumerate(rows[:, 2] - rows[:, 1]):
        b0, b1, b2 = (1.0, -1.0, 0.0) if n == 0 else (1.5, -2.0, 0.5)
        e.append((dt * d - b1 * e[-1] - b2 * e[-2]) / b0)
    return e[-1]


def test_mass_balance_with_a_moving_wall():
    """Production = outflow + pelvis storage + the urine volume's rate S = int J tr(Grad w F^-1) dX (the continuity
    rows' balance, fsi.probes.flux_volume_forms) every step, to the solver's tolerance, on a moving wall. The
    geometric volume int J dX is not the BDF integral of S: the scheme's discrete geometric conservation error,
    second order in dt over the window (observed orders printed)."""
    runs = {dt: moving_wall_pelvis_run(dt) for dt in (0.01, 0.005, 0.0025)}
    scale = max(np.abs(r[:, 1]).max() for r in runs.values())
    closure = max(np.abs(r[:, 0] - r[:, 1]).max() for r in runs.values()) / scale
    flux_closure = max(np.abs(r[:, 3] - r[:, 1]).max() for r in runs.values()) / scale
    gcl = [abs(gcl_volume_error(r, dt)) / (scale * 0.04) for dt, r in runs.items()]
    orders = [math.log(gcl[i] / gcl[i + 1]) / math.log(2.0) for i in range(len(gcl) - 1)]
    print(f"\n[moving wall + pelvis] max |production - storage - Q_out - S| / max|S| = {closure:.1e}; "
          f"|Q_in - Q_out - S| = {flux_closure:.1e}\n  |V - V0 - BDF integral of S| at 0.04 s / (max|S| 0.04 s), "
          f"dt = 0.01, 0.005, 0.0025: {' '.join(f'{e:.2e}' for e in gcl)}, "
          f"orders {' '.join(f'{o:.2f}' for o in orders)}")
    assert closure < 1e-9 and flux_closure < 1e-9
    assert all(o > 1.7 for o in orders)
    # the engine's recorded face flux (the reflux probes') is the study probes' inlet flux (the mesh held on it)
    assert max(np.abs(r[:, 4]).max() for r in runs.values()) < 1e-12 * scale


def test_reflux_at_round_off_is_zero():
    """A part's backflow below REFLUX_FLOOR x the face's flux scale (sum of the parts' |Q|) carries no reflux: a
    state at rest (fluxes ~1e-21 m^3/s of either sign) before the wave adds 0 (it added ~1e-23 m^3 before the
    floor); a backflow above the floor is integrated by the trapezoidal rule."""
    from ureterfsi.study.end_probes import REFLUX_FLOOR, RefluxVolumes
    reflux = RefluxVolumes(2)
    assert reflux.add(0.0, [-1e-21, 3e-21]) == [0.0, 0.0]
    assert reflux.add(0.02, [1e-6, -2e-16]) == [0.0, 0.0]          # 2e-16 < 1e-9 x 1e-6
    assert reflux.add(0.04, [-5e-7, 1e-6]) == [pytest.approx(0.5 * 0.02 * 5e-7, rel=1e-15), 0.0]
    assert 2e-16 < REFLUX_FLOOR * reflux.scale < 5e-7
