#!/usr/bin/env python3
"""Turek-Hron FSI2 / FSI3 (transient, periodic regime): time series of the displacement of point A, drag and
lift; mean +- amplitude [frequency] over the last full periods against the published rows (Turek & Hron 2006
and the finer Featflow level 4, `turek_hron_transient.REFERENCES`) with relative errors, and the cost per period
(wall time, steps, Newton iterations per step).

    .venv/bin/python benchmarks/turek_hron_transient.py --case FSI3 --refinement 0.5 --dt 1e-3 --end 10
    .venv/bin/python benchmarks/turek_hron_transient.py --case FSI3 --start steady --end 2 --json fsi3.json
    .venv/bin/python benchmarks/turek_hron_transient.py --from-json fsi3.json --window 0.5   # table only

--start rest: the benchmark's protocol (inflow ramped over 2 s from rest); --start steady: from the steady
solution at full inflow with a short upward push on the flag (--kick acceleration duration), which reaches
the same periodic regime without the ramp and the slow growth from round-off. Statistics use the series
from t >= end - window (default: the last 40 % of the run) and its last --periods periods of u_y(A) and
lift (twice as many of u_x(A) and drag, which oscillate at twice the frequency).
The JSON holds the series (SI) and the run's cost; it is rewritten every 100 steps while the run goes on.
With --checkpoint a killed run resumes where its last checkpoint left it, and a finished one can be taken
further (a later --end); the wall time counts the steps kept, over all the runs that made them.

    mpiexec -n 2 .venv/bin/python benchmarks/turek_hron_transient.py --case FSI2 --refinement 2 --dt 2e-3 \
        --end 5.2 --start steady --kick 30 0.05 --mesh-motion elastic --mesh-jacobian-stiffening 1 \
        --json fsi2_r2.json --checkpoint fsi2_r2_state.npz
"""
from __future__ import annotations

import argparse
import json
import logging
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from mpi4py import MPI  # noqa: E402

from ureterfsi.data.provenance import atomic_path  # noqa: E402
from ureterfsi.scenes import turek_hron_transient as th  # noqa: E402

SCALE = {"ux_A": (1e3, "mm"), "uy_A": (1e3, "mm"), "drag": (1.0, "N/m"), "lift": (1.0, "N/m")}


def table(case: str, stats: dict, t_from: float, t_end: float, periods: int) -> str:
    """Rows quantity | ours mean +- amplitude [f] (`stats`: th.tail_statistics) | then per published row: its
    values and our relative errors (mean, amplitude, frequency; th.reference_errors)."""
    lines = [f"{case}: statistics over t in [{t_from:.3f}, {t_end:.3f}] s, last {periods} period(s) of u_y "
             f"and lift ({2 * periods} of u_x and drag)"]
    for source, rows in th.REFERENCES.items():
        lines.append(f"{'quantity':>11} {'ours':>34} {source:>34} {'err mean':>9} {'err ampl':>9} {'err f':>7}")
        for k, (scale, unit) in SCALE.items():
            label = f"{k} [{unit}]"
            if isinstance(stats[k], str):
                lines.append(f"{label:>11} {stats[k]}")
                continue
            (m, a, f), (rm, ra, rf) = stats[k], rows[case][k]
            em, ea, ef = th.reference_errors((m, a, f), (rm, ra, rf))
            lines.append(f"{label:>11} {m * scale:10.4g} +- {a * scale:9.4g} [{f:6.3f} Hz] "
                         f"{rm * scale:10.4g} +- {ra * scale:9.4g} [{rf:5.2f} Hz] "
                         f"{100 * em:8.2f}% {100 * ea:8.2f}% {100 * ef:6.2f}%")
    return "\n".join(lines)


def cost(run: dict, frequency: float) -> str:
    steps, wall = run["steps"], run["wall_time"]
    sim = run["end"]
    per_period = 1.0 / frequency
    return (f"cost: {run['dofs']} unknowns, {run['cells']} cells, dt = {run['dt']:g} s, {steps} steps in "
            f"{wall:.0f} s ({wall / steps:.3f} s/step, {run['newton_iterations'] / steps:.2f} Newton iterations "
            f"per step, {run['reduced_steps']} reduced steps); per period of u_y(A) ({per_period:.3f} s): "
            f"{wall * per_period / sim:.0f} s wall, {steps * per_period / sim:.0f} steps")


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--case", choices=sorted(th.CASES), help="FSI3 unless --from-json names it")
    ap.add_argument("--refinement", type=float, default=0.5)
    ap.add_argument("--dt", type=float, default=1e-3, help="time step [s]")
    ap.add_argument("--end", type=float, default=10.0, help="end time [s]")
    ap.add_argument("--start", choices=("rest", "steady"), default="rest")
    ap.add_argument("--kick", type=float, nargs=2, default=(10.0, 0.05), metavar=("ACCEL", "DURATION"),
                    help="--start steady: upward push on the flag [m/s^2] over [s]")
    ap.add_argument("--mesh-motion", choices=("harmonic", "elastic"), default="harmonic")
    ap.add_argument("--mesh-stiffening", type=float, default=1.0, help="exponent q of (V_mean/V_cell)^q")
    ap.add_argument("--mesh-jacobian-stiffening", type=float, default=0.0,
                    help="exponent chi of the deformation-dependent stiffening J^-chi")
    ap.add_argument("--window", type=float, help="statistics over the last WINDOW seconds")
    ap.add_argument("--periods", type=int, default=1)
    ap.add_argument("--json", help="write series and cost here")
    ap.add_argument("--checkpoint", help="checkpoint path: saved every --checkpoint-every steps and at the end; "
                    "a run of the same case, mesh, dt, start and options resumes from it (to its own --end)")
    ap.add_argument("--checkpoint-every", type=int, default=100, help="steps between checkpoints")
    ap.add_argument("--from-json", help="no run: tabulate the series of an earlier --json file")
    args = ap.parse_args(argv)
    comm = MPI.COMM_WORLD
    if args.from_json:
        saved = json.loads(Path(args.from_json).read_text())
        run, series = saved.get("run"), saved.get("series", saved)
        case = run["case"] if run else args.case
        if case is None:
            ap.error(f"{args.from_json} holds a series written while its run went on (no case recorded): give --case")
    else:
        logging.basicConfig(level=logging.INFO if comm.rank == 0 else logging.WARNING,
                            format="%(asctime)s %(message)s", force=True)
        options = th.transient_options(mesh_motion=args.mesh_motion, mesh_stiffening=args.mesh_stiffening,
                                       mesh_jacobian_stiffening=args.mesh_jacobian_stiffening)
        res = th.run_transient(args.case or "FSI3", args.refinement, args.dt, args.end, args.start, tuple(args.kick), comm,
                               options=options, series_path=args.json, checkpoint_path=args.checkpoint,
                               checkpoint_every=args.checkpoint_every)
        case, series = res.case, {k: v.tolist() for k, v in res.series.items()}
        run = {"mesh_motion": args.mesh_motion, "mesh_stiffening": args.mesh_stiffening,
               "mesh_jacobian_stiffening": args.mesh_jacobian_stiffening}
        run.update({k: getattr(res, k) for k in ("case", "refinement", "dt", "end", "start", "dofs", "cells",
                                                 "setup_time", "wall_time", "steps", "newton_iterations",
                                                 "reduced_steps", "min_ale_jacobian", "resumed_from_step")})
        if args.json and comm.rank == 0:
            with atomic_path(args.json) as tmp:
                tmp.write_text(json.dumps({"run": run, "series": series}) + "\n")
    if comm.rank != 0:
        return
    t_end = series["time"][-1]
    t_from = t_end - (args.window if args.window else 0.4 * t_end)
    stats = th.tail_statistics(series, t_from, args.periods)
    print(table(case, stats, t_from, t_end, args.periods))
    if run:
        if isinstance(stats["uy_A"], str):
            print(f"cost: {run['steps']} steps in {run['wall_time']:.0f} s; no period ({stats['uy_A']})")
        else:
            print(cost(run, stats["uy_A"][2]))


if __name__ == "__main__":
    main()
