"""Turek-Hron FSI2 and FSI3 (Turek & Hron 2006): the transient benchmarks in their periodic regime.

A run (`run_transient`) records the displacement of point A, drag, lift and the energies after every step
(`TransientSeries`); `tail_statistics` reduces the series to the benchmark's mean, amplitude and frequency
over the last full periods and `reference_errors` compares them with a published row (`REFERENCES`).
The scene itself (mesh, materials, inflow, forces on the obstacle) is `ureterfsi.scenes.turek_hron`.
"""
from __future__ import annotations

import json
import math
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import ufl
from dolfinx import fem
from mpi4py import MPI

from ureterfsi.fsi import BodyForce, MonolithicFSI, Observer, SolverOptions, TimeIntegrator, TimeSettings
from ureterfsi.fsi import physics
from ureterfsi.data.provenance import atomic_path
from ureterfsi.scenes.turek_hron import (FSI2, FSI3, GEOMETRY, RAMP_TIME, TAGS, ObstacleForces, Tags, build_mesh,
                                        make_scene, point_value, solve_steady_with_continuation)

# Published rows, (mean, amplitude, frequency [Hz]) of the periodic regime per quantity, SI (m, N/m).
# "Turek-Hron 2006": the proposal's finest level (LNCSE 53, 2006, doi 10.1007/3-540-34596-5_15; values as in
# ../shared/reference/fsi-benchmarks.md). "Featflow level 4": the benchmark's finer results on the Featflow page
# (wwwold.mathematik.tu-dortmund.de/~featflow/en/benchmarks/cfdbenchmarking/fsi_benchmark/fsi_tests/
# fsi_fsi_tests.html), level 4+0 (15 872 elements, 304 128 unknowns): FSI2 at dt = 0.5 ms, FSI3 at dt = 0.25 ms;
# read from the tables recorded in solids4foam's HronTurek verification (tutorials/fluidSolidInteraction/
# HronTurek/verification/reference/HronTurek_verification_references.json), FSI3 also in ../shared/reference.
REFERENCES = {
    "Turek-Hron 2006": {
        "FSI2": {"ux_A": (-14.58e-3, 12.44e-3, 3.8), "uy_A": (1.23e-3, 80.6e-3, 2.0),
                 "drag": (208.83, 73.75, 3.8), "lift": (0.88, 234.2, 2.0)},
        "FSI3": {"ux_A": (-2.69e-3, 2.53e-3, 10.9), "uy_A": (1.48e-3, 34.38e-3, 5.3),
                 "drag": (457.3, 22.66, 10.9), "lift": (2.22, 149.78, 5.3)},
    },
    "Featflow level 4": {
        "FSI2": {"ux_A": (-14.85e-3, 12.70e-3, 3.86), "uy_A": (1.30e-3, 81.6e-3, 1.93),
                 "drag": (215.06, 77.65, 3.86), "lift": (0.61, 237.8, 1.93)},
        "FSI3": {"ux_A": (-2.88e-3, 2.72e-3, 10.93), "uy_A": (1.47e-3, 34.99e-3, 5.46),
                 "drag": (460.5, 27.74, 10.93), "lift": (2.50, 153.91, 5.46)},
    },
}
QUANTITIES = ("ux_A", "uy_A", "drag", "lift")
# u_x(A) and drag oscillate at twice the frequency of u_y(A) and lift, and their two lobes per period of the
# flag's swing differ (the motion is not symmetric about y = 0.2): their statistics are over 2 of their
# periods, the same time as one period of u_y, or mean and amplitude depend on which lobe came last
PERIODS_PER_SWING = {"ux_A": 2, "uy_A": 1, "drag": 2, "lift": 1}


def periodic_stats(t, y, periods: int = 1) -> tuple:
    """(mean, amplitude, frequency) of the periodic tail of y(t), as the benchmark defines them: over the
    last `periods` full periods, mean = (max + min)/2 and amplitude = (max - min)/2; frequency = 1/T with T
    the time between the peaks that bound those periods (peak times refined by a parabola through the
    three samples around each maximum). A period is an interval between two up-crossings of the midline
    (max + min)/2 of the second half of the series, with a hysteresis of 10 % of its range, and its peak is
    its maximum."""
    t, y = np.asarray(t, float), np.asarray(y, float)
    tail = y[len(y) // 2:]
    mid, band = 0.5 * (tail.max() + tail.min()), 0.1 * (tail.max() - tail.min())
    ups, below = [], False
    for i, yi in enumerate(y):
        if yi < mid - band:
            below = True
        elif yi > mid + band and below:
            ups.append(i)
            below = False
    peaks = []
    for i0, i1 in zip(ups[:-1], ups[1:]):
        k = i0 + int(np.argmax(y[i0:i1]))
        y0, y1, y2 = y[k - 1], y[k], y[k + 1]
        denom = y0 - 2.0 * y1 + y2
        shift = 0.5 * (y0 - y2) / denom if denom else 0.0
        peaks.append((k, t[k] + shift * 0.5 * (t[k + 1] - t[k - 1])))
    if len(peaks) < periods + 1:
        raise ValueError(f"periodic_stats: {len(peaks)} peaks found, {periods + 1} needed for {periods} period(s)")
    (k0, tp0), (k1, tp1) = peaks[-1 - periods], peaks[-1]
    window = y[k0:k1 + 1]
    return 0.5 * (window.max() + window.min()), 0.5 * (window.max() - window.min()), periods / (tp1 - tp0)


def tail_statistics(series: dict, t_from: float, periods: int = 1) -> dict:
    """{quantity: (mean, amplitude, frequency)} of u_x(A), u_y(A), drag and lift from t >= t_from, over the last
    `periods` periods of the flag's swing (PERIODS_PER_SWING of each quantity's own); a quantity without enough
    periods maps to the ValueError's message."""
    t = np.asarray(series["time"], float)
    keep = t >= t_from
    out = {}
    for k in QUANTITIES:
        try:
            out[k] = periodic_stats(t[keep], np.asarray(series[k], float)[keep], PERIODS_PER_SWING[k] * periods)
        except ValueError as err:
            out[k] = str(err)
    return out


def reference_errors(stats: tuple, reference: tuple) -> tuple:
    """Relative errors (mean, amplitude, frequency) of `stats` against a published (mean, amplitude, frequency).
    A mean near zero (u_y(A), lift) is measured against max(|mean|, amplitude / 10), the scale of the published
    rows' own spread, rather than against itself."""
    (m, a, f), (rm, ra, rf) = stats, reference
    return abs(m - rm) / max(abs(rm), 0.1 * ra), abs(a - ra) / ra, abs(f - rf) / rf


def kick_force(density: float, acceleration: float, duration: float):
    """Body force b = rho_s a sin^2(pi t / tau) e_y for t < tau (zero after): a short upward push on the flag
    that breaks the symmetry of a steady start (a fully developed flow)."""
    def force(X, t):
        pulse = ufl.conditional(ufl.lt(t, duration), ufl.sin(math.pi * t / duration) ** 2, 0.0)
        return ufl.as_vector((0.0, density * acceleration * pulse))
    return force


class TransientSeries(Observer):
    """Time series after every accepted step: displacement of A, drag and lift (variational), and the
    energies E_kin,s = int rho_s |v|^2 / 2, E_el = int mu E:E + lambda tr(E)^2 / 2 (St Venant-Kirchhoff)
    on the flag and E_kin,f = int rho_f J |v|^2 / 2 on the fluid (reference configuration)."""

    names = ("time", "ux_A", "uy_A", "drag", "lift", "solid_kinetic_energy", "elastic_energy",
             "fluid_kinetic_energy")

    def __init__(self, problem: MonolithicFSI, tags: Tags = TAGS, point=GEOMETRY.point_a, path=None,
                 save_every: int = 0):
        self.forces = ObstacleForces(problem, tags)
        self.point, self.path, self.save_every = point, path, save_every
        self.elapsed, self._clock = 0.0, time.perf_counter()    # wall time of the steps since step 0
        scene, ops = problem.scene, problem.ops
        solid = scene.solids[0].material
        X = problem.split()
        v, u = X["velocity"], X["displacement"]
        F = physics.deformation_gradient(ops, u)
        E = 0.5 * (F.T * F - ops.identity())
        dxs, dxf = problem.dx(tuple(problem.solid_tags)), problem.dx(tuple(problem.fluid_tags))
        vv = ufl.dot(ops.vec(v), ops.vec(v))
        self._energy = [fem.form(0.5 * solid.density * vv * ops.weight * dxs),
                        fem.form((solid.lame_mu * ufl.inner(E, E) + 0.5 * solid.lame_lambda * ufl.tr(E) ** 2)
                                 * ops.weight * dxs),
                        fem.form(0.5 * scene.fluid.material.density * ufl.det(F) * vv * ops.weight * dxf)]
        self.data = {k: [] for k in self.names}

    def observe(self, problem, step):
        now = time.perf_counter()
        self.elapsed, self._clock = self.elapsed + (now - self._clock if step else 0.0), now
        uA = point_value(problem.field("displacement"), self.point)
        drag, lift = self.forces.variational()
        energies = [problem.comm.allreduce(fem.assemble_scalar(f), MPI.SUM) for f in self._energy]
        for k, val in zip(self.names, [problem.time, uA[0], uA[1], drag, lift] + energies):
            self.data[k].append(float(val))
        if self.path and self.save_every and step % self.save_every == 0 and problem.comm.rank == 0:
            self.save(self.path)

    def save(self, path):
        """The series so far as JSON {quantity: [values]} (SI), written atomically."""
        with atomic_path(path) as tmp:
            Path(tmp).write_text(json.dumps(self.data) + "\n")

    def arrays(self) -> dict:
        return {k: np.asarray(v) for k, v in self.data.items()}

    def state(self) -> dict:
        """The series and the wall time of the steps it holds (`elapsed`, s; a resumed run adds its own)."""
        return {"data": self.data, "elapsed": self.elapsed}

    def load_state(self, state: dict) -> None:
        self.data = {k: list(state["data"][k]) for k in self.names}
        self.elapsed, self._clock = float(state["elapsed"]), time.perf_counter()

    def cannot_resume(self, state: dict) -> str:
        missing = [k for k in self.names if k not in state.get("data", {})]
        return f"its series lacks {missing[0]!r}" if missing else ""


@dataclass
class TransientResult:
    case: str
    refinement: float
    dt: float
    end: float
    start: str
    dofs: int
    cells: int
    setup_time: float
    wall_time: float
    steps: int
    newton_iterations: int
    reduced_steps: int             # steps shorter than the nominal dt (retries after a Newton failure)
    min_ale_jacobian: float
    series: dict
    resumed_from_step: int = 0     # the checkpoint's step this run went on from (0: from the start)


CASES = {"FSI2": FSI2(), "FSI3": FSI3()}
# choice: MUMPS workspace margin (ICNTL(14), percent over its estimate); the default 20 % fails (INFOG(1) = -9)
# on the first FSI3 Jacobian, whose pivoting at Re = 200 exceeds the estimate
MUMPS_WORKSPACE_PERCENT = 100


def transient_options(**overrides) -> SolverOptions:
    """The engine's options of run_transient: SolverOptions with MUMPS_WORKSPACE_PERCENT (and `overrides`)."""
    return SolverOptions(**({"mumps_workspace_percent": MUMPS_WORKSPACE_PERCENT} | overrides))


def transient_identity(case: str, refinement: float, dt: float, start: str, kick: tuple,
                       options: SolverOptions, ranks: int) -> dict:
    """What determines a run_transient trajectory (its end excepted, so a resumed run may go further)."""
    return {"scene": f"Turek-Hron {case}", "refinement": repr(float(refinement)), "dt": repr(float(dt)),
            "start": start, "kick": repr(tuple(float(k) for k in kick)) if start == "steady" else "-",
            "options": repr(options), "ranks": str(ranks)}


def run_transient(case: str = "FSI3", refinement: float = 0.5, dt: float = 1e-3, end: float = 10.0,
                  start: str = "rest", kick: tuple = (10.0, 0.05), comm=MPI.COMM_WORLD,
                  options: SolverOptions | None = None, max_halvings: int = 4, series_path=None,
                  save_every: int = 100, checkpoint_path=None, checkpoint_every: int = 0) -> TransientResult:
    """Transient FSI2/FSI3 with BDF2 at fixed nominal dt.

    start "rest": the benchmark's protocol, fluid at rest and the inflow ramped over RAMP_TIME;
    start "steady": from the steady solution at full inflow (the unstable symmetric branch), with the flag
    pushed by kick_force(rho_s, *kick) (acceleration [m/s^2], duration [s]) so the oscillation starts at once.
    The periodic regime is the same; "steady" skips the ramp and the slow growth from round-off.
    series_path: the time series is written there (JSON) every `save_every` steps while it runs.
    checkpoint_path: state and series saved every `checkpoint_every` steps and at the end; a run of the same
    transient_identity resumes from it (to this `end`, which may lie beyond the checkpoint's run's).
    options: the engine's options, transient_options() by default."""
    if start not in ("rest", "steady"):
        raise ValueError(f"run_transient start: 'rest' or 'steady', got {start!r}")
    if checkpoint_path and checkpoint_every < 1:
        raise ValueError(f"run_transient checkpoint_every: >= 1 steps with a checkpoint_path, got {checkpoint_every}")
    params = CASES[case]
    options = options or transient_options()
    t0 = time.perf_counter()
    mesh, ct, ft = build_mesh(refinement, comm)
    forces = [BodyForce([TAGS.flag], kick_force(params.rho_s, *kick))] if start == "steady" else []
    scene, inflow = make_scene(mesh, ct, ft, params, ramp_time=RAMP_TIME if start == "rest" else 0.0,
                               body_forces=forces)
    problem = MonolithicFSI(scene, options)
    series = TransientSeries(problem, path=series_path, save_every=save_every)
    settings = TimeSettings(end=end, dt=dt, max_halvings=max_halvings,
                            checkpoint_interval=checkpoint_every if checkpoint_path else 0,
                            checkpoint_path=checkpoint_path,
                            identity=transient_identity(case, refinement, dt, start, kick, options, comm.size))
    integrator = TimeIntegrator(problem, settings, observers=[series])
    if start == "steady" and not integrator.has_checkpoint():
        solve_steady_with_continuation(problem, inflow, amplitudes=(0.25, 0.5, 0.75, 1.0))
    t1 = time.perf_counter()
    records = integrator.run()
    ncells = comm.allreduce(mesh.topology.index_map(2).size_local, MPI.SUM)
    reduced = sum(1 for r in records[:-1] if r.dt < dt * (1.0 - 1e-9))
    return TransientResult(case, refinement, dt, end, start, problem.unknowns, ncells, t1 - t0, series.elapsed,
                           len(records), sum(r.newton_iterations for r in records), reduced,
                           min(r.min_ale_jacobian for r in records), series.arrays(), integrator.resumed_from)
