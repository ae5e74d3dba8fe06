"""Linear solvers of the fully coupled (monolithic ALE) ureter step, side by side: the whole-system MUMPS LU
(`mumps`) against GMRES with the block Gauss-Seidel preconditioner (`block_gauss_seidel`).

Each variant runs in a subprocess of its own (so that its peak memory is its own), in alternating order on
the same mesh: unknowns, the split sizes, Newton and Krylov iterations per step, seconds per step, fresh
Jacobians and factorisations (of each block), where the time went (residual and Jacobian assembly, each block's
factorisation, GMRES), CPU time per step, peak memory (max RSS), and the largest difference of the final state
from the first variant's per field, relative to the field's max norm. On a shared machine compare the ratios
(the CPU ones are the least sensitive to other jobs).

    python benchmarks/coupled_linear_solver.py --config config/config.yaml tests/data/mini-ureter.yaml --steps 4
    python benchmarks/coupled_linear_solver.py --level coarse --variants block_gauss_seidel --steps 3
    python benchmarks/coupled_linear_solver.py --config config/config.yaml tests/data/mini-ureter.yaml --steps 3 \
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
    from ureterfsi.mesh import load_mesh
    from ureterfsi.scenes.ureter import ureter_scene
    from ureterfsi.study.options import solver_options

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
        setattr(options, key, value == "true" if isinstance(current, bool) else type(current)(value))
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
    np.save(args.state, pb.x.x.array)
    np.savez(args.state.replace(".npy", "-fields.npz"),
             **{f: np.asarray(pb.sub(f).collapse()[1]) for f in pb.field_names})
    out = {"variant": args.variant, "unknowns": pb.unknowns, "setup_s": setup, "steady_s": steady,
           "steady_newton": its0, "steps": len(records), "wall_s": wall, "cpu_s": cpu,
           "s_per_step": [r.wall_time for r in records], "newton": [r.newton_iterations for r in records],
           "krylov": krylov.per_step, "counters": dict(pb.counters), "timings": dict(pb.timings),
           "peak_gib": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024**2,
           "jacobian_entries": pb.A.getInfo(PETSc.Mat.InfoType.GLOBAL_SUM)["nz_used"]}
    if pb.linear_solver.sizes is not None:
        out["splits"] = pb.linear_solver.sizes
    print("RESULT " + json.dumps(out))


def report(res, ref):
    """One line per run: unknowns, iterations, time per step (wall and CPU) and where it went, memory, and the
    final state's largest difference from `ref` per field, relative to the field's max norm."""
    import numpy as np
    c, tm = res["counters"], res["timings"]
    blocks = ", ".join(f"{n} {c[f'{n}_factorisations']}" for n in ("solid", "mesh", "flow") if f"{n}_factorisations" in c)
    diff = ", ".join(f"{f} {np.abs(res['state'][d] - ref[d]).max() / np.abs(ref[d]).max():.1e}"
                     for f, d in res["fields"].items() if np.abs(ref[d]).max() > 0)
    print(f"- {res['variant']}: {res['unknowns']} unknowns, set-up {res['setup_s']:.1f} s, steady {res['steady_s']:.1f} s "
          f"({res['steady_newton']} Newton), {res['wall_s'] / res['steps']:.2f} s/step "
          f"{[round(s, 1) for s in res['s_per_step']]} (CPU {res['cpu_s'] / res['steps']:.2f} s/step), "
          f"Newton {res['newton']}, Krylov {res['krylov']}, fresh Jacobians {c['factorisations']}, reused "
          f"{c['reused_solves']}" + (f", block factorisations {blocks}, splits {res['splits']}" if blocks else "")
          + f"; Jacobian entries {res['jacobian_entries']:.3g}, residuals {tm['assemble_residual']:.1f} s, "
          f"Jacobian assembly {tm['assemble_jacobian']:.1f} s, solves with a fresh Jacobian {tm['factorise']:.1f} s, "
          f"kept {tm['solve']:.1f} s"
          + "".join(f", {k} {tm[k]:.1f} s" for k in ("block_extraction", "solid_factorise", "mesh_factorise",
                                                      "flow_factorise", "krylov") if k in tm)
          + f"; peak {res['peak_gib']:.2f} GiB; state vs first: {diff}", flush=True)


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
    ap.add_argument("--repeats", type=int, default=1, help="rounds of the variants, in alternating order")
    ap.add_argument("--krylov-rtol", type=float, default=1e-10)
    ap.add_argument("--variant", help=argparse.SUPPRESS)
    ap.add_argument("--mesh", help=argparse.SUPPRESS)
    ap.add_argument("--state", help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.variant:
        return run_variant(args)

    import netCDF4  # noqa: F401  (before dolfinx)
    import numpy as np

    from ureterfsi.config import load_config_files
    from ureterfsi.mesh import build_mesh

    cfg = load_config_files(args.config)
    with tempfile.TemporaryDirectory() as tmp:
        msh = Path(tmp) / "mesh.msh"
        info = build_mesh(cfg, args.model, args.level, args.symmetry, msh, Path(tmp) / "mesh.json")
        print(f"model {args.model}, level {args.level} ({args.symmetry}), {info['cells_total']} cells, "
              f"{args.steps} steps of dt = {cfg['time']['dt']} s, krylov_rtol {args.krylov_rtol:g}, "
              f"Newton rtol {cfg['solver']['newton_rtol']:g}", flush=True)
        results = []
        for r in range(args.repeats):
            for variant in (args.variants if r % 2 == 0 else args.variants[::-1]):
                state = Path(tmp) / f"variant{args.variants.index(variant)}-{r}.npy"
                cmd = [sys.executable, __file__, "--config", *args.config, "--variant", variant, "--mesh", str(msh),
                       "--state", str(state), "--steps", str(args.steps), "--krylov-rtol", str(args.krylov_rtol)]
                proc = subprocess.run(cmd, capture_output=True, text=True)
                lines = [ln for ln in proc.stdout.splitlines() if ln.startswith("RESULT ")]
                if proc.returncode or not lines:
                    sys.exit(f"variant {variant} failed (exit {proc.returncode}):\n{proc.stderr[-3000:]}")
                res = json.loads(lines[-1][len("RESULT "):])
                res["state"] = np.load(state)
                res["fields"] = dict(np.load(str(state).replace(".npy", "-fields.npz")))
                results.append(res)
                report(res, results[0]["state"])
    by = {v: [r for r in results if r["variant"] == v] for v in args.variants}
    mean = {v: {k: np.mean([r[k] / r["steps"] for r in by[v]]) for k in ("wall_s", "cpu_s")} for v in by}
    peak = {v: max(r["peak_gib"] for r in by[v]) for v in by}
    first = args.variants[0]
    for v in args.variants[1:]:
        print(f"ratio {first} / {v}: time per step {mean[first]['wall_s'] / mean[v]['wall_s']:.2f} (CPU "
              f"{mean[first]['cpu_s'] / mean[v]['cpu_s']:.2f}), peak memory {peak[first] / peak[v]:.2f}")


if __name__ == "__main__":
    main()
