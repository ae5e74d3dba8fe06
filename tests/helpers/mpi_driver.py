"""Run the miniature tube case for a few steps and write its quantities of interest to JSON.

    mpiexec -n 2 python tests/helpers/mpi_driver.py out.json [--steps N] [--dt DT]

Used by tests/fsi/test_mpi.py to compare 1- and 2-process runs. All QoIs are reduced over the ranks
(assemble_scalar + allreduce, MAX/MIN of owned values); rank 0 writes the file.
"""
from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
sys.path.insert(0, str(Path(__file__).resolve().parents[2]))

from mpi4py import MPI  # noqa: E402

from helpers.engine_cases import QoIObserver, Quantities, tube_problem  # noqa: E402
from ureterfsi.fsi import Observer, SolverOptions, TimeIntegrator, TimeSettings  # noqa: E402


class _Kill(Observer):
    def __init__(self, step):
        self.step = step

    def observe(self, problem, step):
        if step == self.step:
            raise KeyboardInterrupt(f"simulated kill after step {step}")


def main(argv=None):
    ap = argparse.ArgumentParser()
    ap.add_argument("output")
    ap.add_argument("--steps", type=int, default=6)
    ap.add_argument("--dt", type=float, default=0.005)
    ap.add_argument("--partition", default=None, choices=[None, "interface", "interface-noghost"],
                    help="'interface': fluid on rank 0, wall on the last rank ('-noghost': without ghost cells)")
    ap.add_argument("--checkpoint", default=None, help="checkpoint path (per-rank files)")
    ap.add_argument("--checkpoint-interval", type=int, default=2)
    ap.add_argument("--kill-at", type=int, default=None,
                    help="simulate a kill (KeyboardInterrupt on every rank) after this step; the JSON then "
                         "holds only {'killed_after': step} (exit code 0: a non-zero exit of one rank makes "
                         "mpiexec abort the others, with a racy exit code)")
    ap.add_argument("--coupling-scheme", default="monolithic", choices=["monolithic", "partitioned"],
                    help="partitioned: block Gauss-Seidel sweeps with Anderson mixing, converged to 1e-10 per field")
    args = ap.parse_args(argv)
    comm = MPI.COMM_WORLD
    t0 = time.perf_counter()
    options = (SolverOptions(coupling_scheme="partitioned", reuse_jacobian=True, newton_field_rtol=1e-10)
               if args.coupling_scheme == "partitioned" else None)
    pb, case = tube_problem(comm, options=options, partition=args.partition)
    obs = QoIObserver(Quantities(pb))
    t_setup = time.perf_counter() - t0
    settings = TimeSettings(end=args.steps * args.dt, dt=args.dt, checkpoint_path=args.checkpoint,
                            checkpoint_interval=args.checkpoint_interval if args.checkpoint else 0)
    try:
        records = TimeIntegrator(pb, settings, [obs, _Kill(args.kill_at)]).run()
    except KeyboardInterrupt:
        comm.Barrier()
        if comm.rank == 0:
            Path(args.output).write_text(json.dumps({"killed_after": args.kill_at, "time": pb.time}))
        return
    out = dict(obs.records)
    out.update({
        "ranks": comm.size,
        "global_dofs": pb.W.dofmap.index_map.size_global * pb.W.dofmap.index_map_bs,
        "newton_iterations": [r.newton_iterations for r in records],
        "residual": [r.residual for r in records],
        "record_min_ale_jacobian": [r.min_ale_jacobian for r in records],
        "state_norm": pb.x.vector.norm(),
        "time": pb.time,
        "setup_seconds": t_setup,
        "run_seconds": time.perf_counter() - t0 - t_setup,
    })
    if comm.rank == 0:
        Path(args.output).write_text(json.dumps(out, indent=1))


if __name__ == "__main__":
    main()
