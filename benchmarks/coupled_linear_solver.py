"""Linear solvers of the fully coupled (monolithic ALE) ureter step, side by side: the whole-system MUMPS LU
(`mumps`) against GMRES with the block Gauss-Seidel preconditioner (`block_gauss_seidel`).

Each variant runs in a subprocess of its own (so that its peak memory is its own), in alternating order on
the same mesh: unknowns, the split sizes, Newton and Krylov iterations per step, seconds per step, fresh
Jacobians and factorisations (of each block), peak memory (max RSS), and the largest difference of the final
state from the first variant's, relative to its max norm. On a shared machine compare the ratios.

    python benchmarks/coupled_linear_solver.py --config config/config.yaml tests/data/mini-ureter.yaml --steps 4
    python benchmarks/coupled_linear_solver.py --level coarse --variants block_gauss_seidel --steps 3
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

    from ureterfsi.config import load_config_files
    from ureterfsi.fsi import Observer, TimeIntegrator, TimeSettings
    from ureterfsi.fsi.problem import MonolithicFSI
    from ureterfsi.mesh import load_mesh
    from ureterfsi.scenes.ureter import ureter_scene
    from ureterfsi.study.options import solver_options

    cfg = load_config_files(args.config)
    cfg["solver"]["linear_solver"] = args.variant
    cfg["solver"]["krylov_rtol"] = args.krylov_rtol
    mesh, ct, ft = load_mesh(Path(args.mesh), MPI.COMM_WORLD)
    t0 = time.perf_counter()
    pb = MonolithicFSI(ureter_scene(cfg, mesh, ct, ft), solver_options(cfg))
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

    for k in pb.counters:
        pb.counters[k] = 0
    krylov = Krylov()
    dt = cfg["time"]["dt"]
    t0 = time.perf_counter()
    records = TimeIntegrator(pb, TimeSettings(end=args.steps * dt, dt=dt), observers=[krylov]).run()
    wall = time.perf_counter() - t0
    np.save(args.state, pb.x.x.array)
    out = {"variant": args.variant, "unknowns": pb.unknowns, "setup_s": setup, "steady_s": steady,
           "steady_newton": its0, "steps": len(records), "wall_s": wall,
           "s_per_step": [r.wall_time for r in records], "newton": [r.newton_iterations for r in records],
           "krylov": krylov.per_step, "counters": dict(pb.counters), "timings": dict(pb.timings),
           "peak_gib": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024**2}
    if pb.coupled_solver is not None:
        out["splits"] = pb.coupled_solver.sizes
    print("RESULT " + json.dumps(out))


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--config", nargs="+", default=[str(ROOT / "config/config.yaml")])
    ap.add_argument("--model", default="3")
    ap.add_argument("--level", default="coarse")
    ap.add_argument("--symmetry", default="quarter")
    ap.add_argument("--steps", type=int, default=4)
    ap.add_argument("--variants", nargs="+", default=["mumps", "block_gauss_seidel"],
                    choices=["mumps", "block_gauss_seidel"])
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
        results = []
        for r in range(args.repeats):
            for variant in (args.variants if r % 2 == 0 else args.variants[::-1]):
                state = Path(tmp) / f"{variant}-{r}.npy"
                cmd = [sys.executable, __file__, "--config", *args.config, "--variant", variant, "--mesh", str(msh),
                       "--state", str(state), "--steps", str(args.steps), "--krylov-rtol", str(args.krylov_rtol)]
                proc = subprocess.run(cmd, capture_output=True, text=True)
                lines = [ln for ln in proc.stdout.splitlines() if ln.startswith("RESULT ")]
                if proc.returncode or not lines:
                    sys.exit(f"variant {variant} failed (exit {proc.returncode}):\n{proc.stderr[-3000:]}")
                res = json.loads(lines[-1][len("RESULT "):])
                res["state"] = np.load(state)
                results.append(res)
    ref = results[0]["state"]
    print(f"model {args.model}, level {args.level} ({args.symmetry}), {info['cells_total']} cells, "
          f"{results[0]['unknowns']} unknowns, {args.steps} steps of dt = {cfg['time']['dt']} s, "
          f"krylov_rtol {args.krylov_rtol:g}, Newton rtol {cfg['solver']['newton_rtol']:g}")
    for res in results:
        c, tm = res["counters"], res["timings"]
        blocks = ", ".join(f"{n} {c[f'{n}_factorisations']}" for n in ("solid", "mesh", "flow")
                           if f"{n}_factorisations" in c)
        diff = float(np.abs(res["state"] - ref).max() / np.abs(ref).max())
        print(f"- {res['variant']}: set-up {res['setup_s']:.1f} s, steady {res['steady_s']:.1f} s "
              f"({res['steady_newton']} Newton), {res['wall_s'] / res['steps']:.2f} s/step "
              f"{[round(s, 1) for s in res['s_per_step']]}, Newton {res['newton']}, Krylov {res['krylov']}, "
              f"fresh Jacobians {c['factorisations']}, reused {c['reused_solves']}"
              + (f", block factorisations {blocks}, splits {res['splits']}" if blocks else "")
              + f"; assembly {tm['assemble_jacobian']:.1f} s, with fresh Jacobian {tm['factorise']:.1f} s, "
              f"kept {tm['solve']:.1f} s; peak {res['peak_gib']:.2f} GiB; state vs first {diff:.1e}")
    if len(args.variants) == 2:
        by = {v: [r for r in results if r["variant"] == v] for v in args.variants}
        a, b = (np.mean([r["wall_s"] / r["steps"] for r in by[v]]) for v in args.variants)
        ma, mb = (max(r["peak_gib"] for r in by[v]) for v in args.variants)
        print(f"ratio {args.variants[0]} / {args.variants[1]}: time per step {a / b:.2f}, peak memory {ma / mb:.2f}")


if __name__ == "__main__":
    main()
