"""The command line of a study run, every rung: `python -m ureterfsi.study --model M --level L --symmetry S
--mesh F --out F [--fidelity one_way --wall F]` (every solve rule, through ureterfsi.workflow.launch): its
arguments, then study.run.solve. A solve that fails ends in one line on stderr, named by --name if given; with
--record-failure its run file holds the failure instead (study.run.write_failed_run) and the command succeeds."""
from __future__ import annotations

import argparse
import json
import logging
import sys

from mpi4py import MPI

from ureterfsi.data.checked import BadFile
from ..config import ConfigError, load_config, load_config_files, read_run_config, run_config
from ..fsi import SolveFailure
from .options import FIDELITIES, RunSpec
from .oneway import MeshMotionRefused
from .run import solve, write_failed_run


def configure_logging(stream=None) -> None:
    """Progress lines of the engine and the study on rank 0 (warnings from every rank)."""
    rank = MPI.COMM_WORLD.rank
    handler = logging.StreamHandler(stream)
    handler.setFormatter(logging.Formatter("%(asctime)s %(name)s: %(message)s", "%H:%M:%S"))
    for name in ("ureterfsi",):
        lg = logging.getLogger(name)
        lg.handlers[:] = [handler]
        lg.setLevel(logging.INFO if rank == 0 else logging.WARNING)
        lg.propagate = False


def parser() -> argparse.ArgumentParser:
    """The arguments of `python -m ureterfsi.study` (ureterfsi.workflow.launch builds them for the rules)."""
    ap = argparse.ArgumentParser(prog="python -m ureterfsi.study",
                                 description="FSI solve of one stent model on one mesh (fully coupled or one-way).")
    ap.add_argument("--config", nargs="+", default=["config/config.yaml"], help="config file and overlays")
    ap.add_argument("--config-json", default=None, help="the whole configuration as JSON")
    ap.add_argument("--run-config", default=None,
                    help="the sections this solve reads as JSON (ureterfsi.config.run_sections; rule solve)")
    ap.add_argument("--run-sections", default=None,
                    help="the same sections as JSON text (a design point's or corner's own configuration)")
    ap.add_argument("--model", required=True)
    ap.add_argument("--level", required=True)
    ap.add_argument("--symmetry", required=True)
    ap.add_argument("--mesh", required=True, help="gmsh .msh file of the model")
    ap.add_argument("--out", required=True, help="netCDF output")
    ap.add_argument("--checkpoint", default=None, help="checkpoint path (resumes if present)")
    ap.add_argument("--end", type=float, default=None, help="override time.end (s)")
    ap.add_argument("--dt", type=float, default=None, help="override time.dt (s)")
    ap.add_argument("--wall", default=None,
                    help="one_way: the wall-motion dataset to read (rule wall_motion, "
                         "ureterfsi.study.oneway.write_wall_motion) instead of solving the wall")
    ap.add_argument("--fidelity", choices=FIDELITIES, default="fully_coupled",
                    help="fully_coupled (monolithic ALE FSI) or one_way (wall -> urine -> stent, "
                         "ureterfsi.study.oneway)")
    ap.add_argument("--out-of-core", type=int, choices=(0, 1), default=0,
                    help="fully_coupled: 1, MUMPS writes its factors to disk (a job given less memory than the run "
                         "needs; the same solution, slower)")
    ap.add_argument("--name", default=None, help="what a failure names (e.g. 'design point S/P')")
    ap.add_argument("--record-failure", action="store_true",
                    help="a failed solve writes its run file holding the failure (attribute solve_failed) and exits 0")
    return ap


def main(argv=None) -> int:
    args = parser().parse_args(argv)
    configure_logging()
    try:
        if args.run_config:
            cfg = read_run_config(args.run_config, args.model)
        elif args.run_sections:
            cfg = run_config(json.loads(args.run_sections), args.model)
        elif args.config_json:
            with open(args.config_json) as fh:
                cfg = load_config(json.load(fh))
        else:
            cfg = load_config_files(args.config)
    except ConfigError as err:
        print(err, file=sys.stderr)
        return 2
    spec = RunSpec(args.model, args.level, args.symmetry, args.mesh, args.end, args.dt, bool(args.out_of_core))
    try:
        solve(cfg, spec, args.fidelity, args.out, args.checkpoint, args.wall)
    except (BadFile, SolveFailure) as err:
        what = "refused before the solve" if isinstance(err, MeshMotionRefused) else f"({args.fidelity}) failed"
        line = f"{args.name} {what}: {err}" if args.name else str(err)
        if args.record_failure and isinstance(err, SolveFailure):
            logging.getLogger("ureterfsi").error("%s, recorded as such in %s", line, args.out)
            if MPI.COMM_WORLD.rank == 0:
                write_failed_run(cfg, args.out, args.fidelity, f"{what}: {err}")
            return 0
        if MPI.COMM_WORLD.rank == 0:
            print(line, file=sys.stderr)
        return 1
    return 0
