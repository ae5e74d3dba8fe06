"""Cost of the stent-surface probes (ureterfsi.study.stent_surface) against a fully coupled time step.

Per step, side by side in one process: the step (Newton solve), the whole probe observation, and within it the
stent's wall shear stress (WallShear assembly on the FLUID_STENT facets, region means, time integrals) and the
holes' channel fluxes (net and gross: the gross is the new half). Prints the medians and their shares of a step.

    python benchmarks/stent_surface_cost.py --config config/config.yaml config/segment-10mm.yaml --steps 4
"""
from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

import netCDF4  # noqa: F401  (before dolfinx)
import numpy as np
from mpi4py import MPI

from ureterfsi.config import load_config_files
from ureterfsi.fsi.problem import MonolithicFSI
from ureterfsi.mesh.build import build_mesh
from ureterfsi.mesh.geometry import StentModel
from ureterfsi.mesh.io import load_mesh
from ureterfsi.scenes.ureter import ureter_scene
from ureterfsi.study.options import solver_options
from ureterfsi.study.probes import UreterProbes

ROOT = Path(__file__).resolve().parent.parent


def timed(f):
    t0 = time.perf_counter()
    f()
    return time.perf_counter() - t0


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--config", nargs="+", default=[str(ROOT / "config/config.yaml")])
    ap.add_argument("--model", default="3")
    ap.add_argument("--level", default="coarse")
    ap.add_argument("--steps", type=int, default=4)
    ap.add_argument("--dt", type=float, default=0.02)
    args = ap.parse_args()
    comm = MPI.COMM_WORLD
    cfg = load_config_files(args.config)
    with tempfile.TemporaryDirectory() as tmp:
        msh = Path(tmp) / "mesh.msh"
        if comm.rank == 0:
            build_mesh(cfg, args.model, args.level, "quarter", msh, Path(tmp) / "mesh.json")
        comm.Barrier()
        mesh, ct, ft = load_mesh(msh, comm)
    pb = MonolithicFSI(ureter_scene(cfg, mesh, ct, ft), solver_options(cfg, fully_coupled=True))
    obs = UreterProbes(pb, cfg, StentModel.from_config(cfg, args.model), "quarter", [])
    pb.solve_steady()
    obs.observe(pb, 0)                       # compiles nothing more: the forms are compiled in the constructor
    rows = []
    for k in range(1, args.steps + 1):
        step = timed(lambda: pb.step(args.dt))
        probes = timed(lambda: obs.observe(pb, k))
        wss = timed(lambda: obs.surface.observe(pb.time))
        channels = timed(obs.hole_channels)
        rows.append((step, probes, wss, channels))
    step, probes, wss, channels = np.median(np.array(rows), axis=0)
    facets = comm.allreduce(obs.surface.wss.unit_cells.size)
    if comm.rank == 0:
        print(f"model {args.model}, {args.level} quarter, {pb.unknowns} unknowns, {facets} stent wall units, "
              f"{len(obs.holes)} holes, medians over {args.steps} steps")
        print(f"  step (Newton)           {step:8.4f} s")
        print(f"  all probes              {probes:8.4f} s  {probes / step:7.2%} of a step")
        print(f"  stent WSS               {wss:8.4f} s  {wss / step:7.2%} of a step")
        print(f"  hole net + gross flux   {channels:8.4f} s  {channels / step:7.2%} of a step (gross: half)")


if __name__ == "__main__":
    main()
