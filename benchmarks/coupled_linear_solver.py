"""Linear solvers of the fully coupled (monolithic ALE) ureter step, side by side: the whole-system MUMPS LU
(`mumps`) against GMRES with the block Gauss-Seidel preconditioner (`block_gauss_seidel`).

Each variant runs in a subprocess of its own (so that its peak memory is its own), in alternating order on
the same mesh: unknowns, the split sizes, Newton and Krylov iterations per step, seconds per step, fresh
Jacobians and factorisations (of each block), where the time went (residual and Jacobian assembly, each block's
factorisation, GMRES), CPU time per step (of the busiest rank and of all), peak memory (max RSS, summed over the
ranks), and the largest difference of the final state from the first run's per field, relative to the field's max
norm (fields ordered by dof coordinates, so runs on different process counts compare), and of the lumped end
conditions' face pressures and fluxes (fsi.end_conditions), where the scene has them. `--processes 1 2` runs each
variant on 1 and on 2 MPI processes. On a shared machine compare the ratios
(the CPU ones are the least sensitive to other jobs).

    python benchmarks/coupled_linear_solver.py --config config/config.yaml config/segment-10mm.yaml --steps 4
    python benchmarks/coupled_linear_solver.py --level coarse --variants block_gauss_seidel --steps 3
    python benchmarks/coupled_linear_solver.py --config config/config.yaml config/segment-10mm.yaml --steps 2 \
        --variants block_gauss_seidel:krylov_forcing=eisenstat_walker --processes 1 2
    python benchmarks/coupled_linear_solver.py --config config/config.yaml config/segment-10mm.yaml --steps 3 \
        --variants mumps mumps:jacobian_sparsity=mixed_element block_gauss_seidel:krylov_forcing=eisenstat_walker
"""
from __future__ import annotations

import argparse
import json
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def run_variant(args):
    import netCDF4  # noqa: F401  (before dolfinx)
    import numpy as np
    from mpi4py import MPI
    from petsc4py import PETSc

    from ureterfsi.config import load_config_files
    from ureterfsi.fsi import Observer, TimeIntegrator, TimeSettings
    from ureterfsi.fsi.problem import MonolithicFSI
    from ureterfsi.mesh.io import load_mesh
    from ureterfsi.scenes.ureter import ureter_scene
    from ureterfsi.study.cli import configure_logging
    from ureterfsi.study.options import solver_options

    configure_logging()
    cfg = load_config_files(args.config)
    solver, _, overrides = args.variant.partition(":")
    cfg["solver"]["linear_solver"] = solver
    cfg["solver"]["krylov_rtol"] = args.krylov_rtol
    mesh, ct, ft = load_mesh(Path(args.mesh), MPI.COMM_WORLD)
    t0 = time.perf_counter()
    options = solver_options(cfg)
    for item in filter(None, overrides.split(",")):
        key, _, value = item.partition("=")
        current = getattr(options, key)
        setattr(options, key, None if value == "none" else value == "true" if isinstance(current, bool)
                else float(value) if current is None else type(current)(value))
    pb = MonolithicFSI(ureter_scene(cfg, mesh, ct, ft), options)
    setup = time.perf_counter() - t0
    t0 = time.perf_counter()
    its0, _ = pb.solve_steady()
    steady = time.perf_counter() - t0

    class Krylov(Observer):
        def __init__(self):
            self.per_step, self.last = [], 0

        def observe(self, problem, step):
            k = problem.counters.get("krylov_iterations", 0)
            if step:
                self.per_step.append(k - self.last)
            self.last = k

    for d in (pb.counters, pb.timings):
        for k in d:
            d[k] = 0
    krylov = Krylov()
    dt = cfg["time"]["dt"]
    t0, cpu0 = time.perf_counter(), time.process_time()
    records = TimeIntegrator(pb, TimeSettings(end=args.steps * dt, dt=dt), observers=[krylov]).run()
    wall, cpu = time.perf_counter() - t0, time.process_time() - cpu0
    comm = MPI.COMM_WORLD
    fields = {f: field_values(pb, f, comm) for f in pb.field_names}
    peak = comm.allreduce(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024**2)
    out = {"variant": args.variant, "processes": comm.size, "unknowns": pb.unknowns, "setup_s": setup,
           "steady_s": steady, "steady_newton": its0, "steps": len(records), "wall_s": comm.allreduce(wall, MPI.MAX),
           "cpu_s": comm.allreduce(cpu, MPI.MAX), "cpu_total_s": comm.allreduce(cpu),
           "s_per_step": [r.wall_time for r in records], "newton": [r.newton_iterations for r in records],
           "krylov": krylov.per_step, "counters": dict(pb.counters), "timings": dict(pb.timings),
           "end_pressures": pb.end_conditions.p.tolist(), "end_fluxes": pb.end_conditions.q.tolist(),
           "peak_gib": peak, "jacobian_entries": (pb.A.getInfo(PETSc.Mat.InfoType.GLOBAL_SUM)["nz_used"]
                                                   if pb.partitioned is None else 0)}
    if pb.partitioned is not None:
        out["splits"] = pb.partitioned.sizes
    elif pb.linear_solver.sizes is not None:
        out["splits"] = pb.linear_solver.sizes
    if comm.rank == 0:
        np.savez(args.state, **fields)
        print("RESULT " + json.dumps(out))


def field_values(pb, name, comm):
    """The owned values of field `name` on all ranks, ordered by (component, dof coordinates): the same order
    whatever the partition, so that runs on different process counts compare entry by entry."""
    import numpy as np
    V, dofs = pb.sub(name).collapse()
    n, bs = V.dofmap.index_map.size_local, V.dofmap.index_map_bs
    xyz = np.round(V.tabulate_dof_coordinates()[:n], 12)
    values = pb.x.x.array[np.asarray(dofs)[:n * bs]].reshape(n, bs)
    parts = comm.gather((xyz, values))
    if comm.rank:
        return None
    xyz, values = (np.concatenate(a) for a in zip(*parts))
    order = np.lexsort(xyz.T[::-1])
    return values[order].T.ravel()


def report(res, ref):
    """One line per run: unknowns, iterations, time per step (wall and CPU) and where it went, memory, and the
    final state's largest difference from `ref`'s per field, relative to the field's max norm, and the lumped end
    conditions' face pressures and fluxes (fsi.end_conditions) with their largest relative difference from `ref`'s."""
    import numpy as np
    c, tm = res["counters"], res["timings"]
    blocks = ", ".join(f"{n} {c[f'{n}_factorisations']}" for n in ("solid", "mesh", "flow") if f"{n}_factorisations" in c)
    diff = ", ".join(f"{f} {np.abs(a - ref['state'][f]).max() / np.abs(ref['state'][f]).max():.1e}"
                     for f, a in res["state"].items() if np.abs(ref["state"][f]).max() > 0)
    ends = "".join(f"; lumped ends' {k.split('_')[1]} {[float(f'{v:.7g}') for v in res[k]]} (vs first: "
                   f"{np.abs(np.subtract(res[k], ref[k])).max() / np.abs(ref[k]).max():.1e})"
                   for k in ("end_pressures", "end_fluxes") if res[k])
    print(f"- {res['variant']}, {res['processes']} process(es): {res['unknowns']} unknowns, set-up {res['setup_s']:.1f} s, steady {res['steady_s']:.1f} s "
          f"({res['steady_newton']} Newton), {res['wall_s'] / res['steps']:.2f} s/step "
          f"{[round(s, 1) for s in res['s_per_step']]} (CPU {res['cpu_s'] / res['steps']:.2f} s/step on the "
          f"busiest rank, {res['cpu_total_s'] / res['steps']:.2f} on all), "
          f"Newton {res['newton']}, Krylov {res['krylov']}, fresh Jacobians {c['factorisations']}, reused "
          f"{c['reused_solves']}" + (f", block factorisations {blocks}, splits {res['splits']}" if blocks else "")
          + ("".join(f", {k} {c[k]}" for k in ("sweeps", "solid_solves", "mesh_solves", "flow_solves") if k in c))
          + f"; Jacobian entries {res['jacobian_entries']:.3g}, residuals {tm['assemble_residual']:.1f} s, "
          f"Jacobian assembly {tm['assemble_jacobian']:.1f} s, solves with a fresh Jacobian {tm['factorise']:.1f} s, "
          f"kept {tm['solve']:.1f} s"
          + "".join(f", {k} {tm[k]:.1f} s" for k in ("block_extraction", "solid_factorise", "mesh_factorise",
                                                      "flow_factorise", "krylov", "solid_solve", "flow_solve",
                                                      "assemble_flow_jacobian", "assemble_solid_jacobian",
                                                      "assemble_block_rows") if k in tm)
          + f"; peak {res['peak_gib']:.2f} GiB; state vs first: {diff}" + ends, flush=True)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--config", nargs="+", default=[str(ROOT / "config/config.yaml")])
    ap.add_argument("--model", default="3")
    ap.add_argument("--level", default="coarse")
    ap.add_argument("--symmetry", default="quarter")
    ap.add_argument("--steps", type=int, default=4)
    ap.add_argument("--variants", nargs="+", default=["mumps", "block_gauss_seidel"],
                    help="linear_solver[:SolverOptions overrides], e.g. mumps:jacobian_sparsity=mixed_element or "
                         "block_gauss_seidel:krylov_forcing=eisenstat_walker,krylov_refactorise_iterations=20")
    ap.add_argument("--processes", nargs="+", type=int, default=[1],
                    help="MPI process counts to run each variant on (mpiexec above 1)")
    ap.add_argument("--repeats", type=int, default=1, help="rounds of the variants, in alternating order")
    ap.add_argument("--krylov-rtol", type=float, default=1e-10)
    ap.add_argument("--variant", help=argparse.SUPPRESS)
    ap.add_argument("--mesh", help="a mesh built before (rule mesh: .msh with its .json beside it) instead of "
                                   "building one for --model/--level/--symmetry")
    ap.add_argument("--state", help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.variant:
        return run_variant(args)

    import netCDF4  # noqa: F401  (before dolfinx)
    import numpy as np

    from ureterfsi.config import load_config_files
    from ureterfsi.mesh.build import build_mesh

    cfg = load_config_files(args.config)
    with tempfile.TemporaryDirectory() as tmp:
        msh = Path(args.mesh or Path(tmp) / "mesh.msh")
        if args.mesh:
            info = json.loads(msh.with_suffix(".json").read_text())
        else:
            info = build_mesh(cfg, args.model, args.level, args.symmetry, msh, Path(tmp) / "mesh.json")
        print(f"model {args.model}, level {args.level} ({args.symmetry}), {info['cells_total']} cells, "
              f"{args.steps} steps of dt = {cfg['time']['dt']} s, krylov_rtol {args.krylov_rtol:g}, "
              f"Newton rtol {cfg['solver']['newton_rtol']:g}", flush=True)
        runs = [(v, n) for v in args.variants for n in args.processes]
        results = []
        for r in range(args.repeats):
            for variant, n in (runs if r % 2 == 0 else runs[::-1]):
                state = Path(tmp) / f"run{runs.index((variant, n))}-{r}.npz"
                mpi = ["mpiexec", "-n", str(n), "--allow-run-as-root", "--oversubscribe"] if n > 1 else []
                cmd = [*mpi, sys.executable, __file__, "--config", *args.config, "--variant", variant, "--mesh",
                       str(msh), "--state", str(state), "--steps", str(args.steps), "--krylov-rtol",
                       str(args.krylov_rtol)]
                proc = subprocess.run(cmd, stdout=subprocess.PIPE, text=True)  # its log goes to stderr
                lines = [ln for ln in proc.stdout.splitlines() if ln.startswith("RESULT ")]
                if proc.returncode or not lines:
                    sys.exit(f"variant {variant} on {n} process(es) failed (exit {proc.returncode})")
                res = json.loads(lines[-1][len("RESULT "):])
                res["state"] = dict(np.load(state))
                results.append(res)
                report(res, results[0])
    by = {run: [r for r in results if (r["variant"], r["processes"]) == run] for run in runs}
    mean = {run: {k: np.mean([r[k] / r["steps"] for r in by[run]]) for k in ("wall_s", "cpu_s", "cpu_total_s")}
            for run in by}
    peak = {run: max(r["peak_gib"] for r in by[run]) for run in by}
    first = runs[0]
    for run in runs[1:]:
        print(f"ratio {first} / {run}: time per step {mean[first]['wall_s'] / mean[run]['wall_s']:.2f} (CPU of the "
              f"busiest rank {mean[first]['cpu_s'] / mean[run]['cpu_s']:.2f}, of all ranks "
              f"{mean[first]['cpu_total_s'] / mean[run]['cpu_total_s']:.2f}), peak memory "
              f"{peak[first] / peak[run]:.2f}")

if __name__ == "__main__":
    main()
