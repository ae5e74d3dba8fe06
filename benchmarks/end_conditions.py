"""Cost per time step of the lumped end conditions (fsi.end_conditions) against plain open boundaries, side by side.

The rigid axisymmetric pipe (scenes.rigid_pipe) with n cells across its radius, urine-like fluid, driven by a
pressure difference: `open`, both faces at constant normal stresses; `lumped`, a compartment (C dp/dt = Q_prod - Q_in)
at the inlet and a one-way valve at the outlet, coupled implicitly (the Jacobian's rank-2 term by the Woodbury
identity on the kept factorisation). Both run the same steps in one process, alternately (A B A B ...), and the
median wall time per step of each and their ratio are printed, with the Newton work of each.

    python benchmarks/end_conditions.py --n 16 --steps 10 --repeats 3 [--reuse-jacobian]
"""
from __future__ import annotations

import argparse
import statistics
import time

from ureterfsi.fsi import Compartment, MonolithicFSI, NewtonianFluid, OpenBoundary, SolverOptions, Valve
from ureterfsi.scenes.rigid_pipe import INLET, OUTLET, RigidPipe, rigid_pipe_scene

URINE = NewtonianFluid(density=1050.0, dynamic_viscosity=1.3e-3)


def problem(kind: str, n: int, reuse: bool) -> MonolithicFSI:
    """The pipe at rest under a 10 Pa pressure difference (the flow develops over its viscous time, 0.8 s)."""
    pipe = RigidPipe(fluid=URINE)
    R = pipe.resistance
    if kind == "open":
        ends = (OpenBoundary([INLET], 10.0), OpenBoundary([OUTLET], 0.0))
    else:
        ends = (OpenBoundary([INLET], condition=Compartment(0.1 / R, lambda t: 1.0 / R, 10.0)),
                OpenBoundary([OUTLET], condition=Valve(lambda t: 0.0, R, 1e3 * R, 1.0)))
    return MonolithicFSI(rigid_pipe_scene(pipe, n, *ends), SolverOptions(reuse_jacobian=reuse))


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=16, help="cells across the radius")
    ap.add_argument("--steps", type=int, default=10)
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--dt", type=float, default=0.01)
    ap.add_argument("--reuse-jacobian", action="store_true", help="keep the factorisation across steps (the study's)")
    args = ap.parse_args()
    times = {"open": [], "lumped": []}
    work = {}
    for _ in range(args.repeats):
        for kind in times:
            pb = problem(kind, args.n, args.reuse_jacobian)
            for _ in range(args.steps):
                t0 = time.perf_counter()
                pb.step(args.dt)
                times[kind].append(time.perf_counter() - t0)
            work[kind] = dict(pb.counters) | {"unknowns": pb.unknowns}
    med = {k: statistics.median(v) for k, v in times.items()}
    print(f"rigid pipe, {args.n} cells across, {args.steps} steps x {args.repeats} repeats, alternating, "
          f"reuse_jacobian {args.reuse_jacobian}")
    for kind in times:
        print(f"  {kind:7s} median {1e3 * med[kind]:.2f} ms/step (min {1e3 * min(times[kind]):.2f}, "
              f"max {1e3 * max(times[kind]):.2f}); last repeat's work {work[kind]}")
    print(f"  lumped / open per step: {med['lumped'] / med['open']:.3f}")


if __name__ == "__main__":
    main()
