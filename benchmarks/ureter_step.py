"""Cost of a fully coupled time step of the ureter scene.

Reports degrees of freedom, set-up (form compilation) time, the initial steady solve, seconds per time
step, Newton iterations per step, the share of residual assembly / Jacobian assembly / LU factorisation /
solves with a reused factorisation, and the peak memory (max RSS) of the process.

    python benchmarks/ureter_step.py --level coarse --steps 5
    python benchmarks/ureter_step.py --config config/config.yaml config/segment-10mm.yaml --steps 4
    python benchmarks/ureter_step.py --no-reuse ...          # full Newton: a factorisation per iteration
"""
from __future__ import annotations

import argparse
import resource
import tempfile
import time
from pathlib import Path

import netCDF4  # noqa: F401  (before dolfinx)
from mpi4py import MPI

from ureterfsi.config import load_config_files
from ureterfsi.fsi import TimeIntegrator, TimeSettings
from ureterfsi.fsi.problem import MonolithicFSI
from ureterfsi.mesh.build import build_mesh
from ureterfsi.mesh.io import load_mesh
from ureterfsi.scenes.ureter import ureter_scene
from ureterfsi.study.options import solver_options

ROOT = Path(__file__).resolve().parent.parent


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--config", nargs="+", default=[str(ROOT / "config/config.yaml")])
    ap.add_argument("--model", default="3")
    ap.add_argument("--level", default="coarse")
    ap.add_argument("--symmetry", default="quarter")
    ap.add_argument("--steps", type=int, default=5)
    ap.add_argument("--no-reuse", action="store_true", help="refactorise the Jacobian at every iteration")
    args = ap.parse_args()
    comm = MPI.COMM_WORLD
    cfg = load_config_files(args.config)
    cfg["solver"]["reuse_jacobian"] = not args.no_reuse
    with tempfile.TemporaryDirectory() as tmp:
        msh = Path(tmp) / "mesh.msh"
        if comm.rank == 0:
            info = build_mesh(cfg, args.model, args.level, args.symmetry, msh, Path(tmp) / "mesh.json")
        comm.Barrier()
        mesh, ct, ft = load_mesh(msh, comm)
    t0 = time.perf_counter()
    pb = MonolithicFSI(ureter_scene(cfg, mesh, ct, ft, axisymmetric=args.symmetry == "axisymmetric"),
                       solver_options(cfg))
    setup = time.perf_counter() - t0
    t0 = time.perf_counter()
    its0, _ = pb.solve_steady()
    steady = time.perf_counter() - t0
    for k in pb.timings:
        pb.timings[k] = 0.0
    for k in pb.counters:
        pb.counters[k] = 0
    dt = cfg["time"]["dt"]
    t0 = time.perf_counter()
    records = TimeIntegrator(pb, TimeSettings(end=args.steps * dt, dt=dt)).run()
    wall = time.perf_counter() - t0
    peak = comm.allreduce(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss, op=MPI.SUM) / 1024**2
    if comm.rank:
        return
    dofs = pb.W.dofmap.index_map.size_global * pb.W.dofmap.index_map_bs
    cells = mesh.topology.index_map(3 if args.symmetry != "axisymmetric" else 2).size_global
    print(f"model {args.model}, level {args.level} ({args.symmetry}), {comm.size} process(es), "
          f"Jacobian reuse {'off' if args.no_reuse else 'on'}")
    print(f"  cells {cells}, dofs {dofs}, mesh generation {info['mesh_wall_time_s']:.1f} s")
    print(f"  set-up (forms, spaces) {setup:.1f} s; initial steady solve {steady:.1f} s ({its0} Newton iterations)")
    print(f"  {len(records)} steps in {wall:.1f} s: {wall / len(records):.2f} s/step, Newton iterations per step "
          f"{[r.newton_iterations for r in records]}")
    total = sum(pb.timings.values())
    shares = ", ".join(f"{k} {v:.1f} s ({100 * v / total:.0f}%)" for k, v in pb.timings.items())
    print(f"  time in the step loop: {shares}")
    print(f"  factorisations {pb.counters['factorisations']}, solves with a reused factorisation "
          f"{pb.counters['reused_solves']}")
    print(f"  peak memory (max RSS summed over processes) {peak:.2f} GiB")


if __name__ == "__main__":
    main()
