"""Linear solvers of the one-way urine system (fluid alone, segregated mesh motion): direct LU vs fieldsplit.

Builds the urine problem of a study mesh as the one-way rung does (wall motion from the r-z wall solve),
advances a few steps with the configured solver, then solves one and the same Newton system (Jacobian and
residual at the next step) with each variant and reports the first solve (with the factorisation or the
preconditioner set-up), a second solve with them kept, Krylov iterations, the memory MUMPS reports for its
factorisation (INFOG(22), MB), the process's peak memory so far and the solution's relative difference from
the exact flow-block LU's (when lu_flow is among the variants, run first). Variants: LU of the whole mixed system,
LU of the flow block alone (the engine's direct solve), the same with MUMPS's block low-rank (BLR)
compression at two dropping tolerances, GMRES + Schur fieldsplit with ILU(0) (the engine's
`fieldsplit`) or BoomerAMG on the velocity block. The fieldsplit variants stop at the configured krylov_rtol.

    python benchmarks/fluid_linear_solver.py --level coarse
    python benchmarks/fluid_linear_solver.py --level medium --variants lu_flow fieldsplit_ilu
    python benchmarks/fluid_linear_solver.py --level medium --variants lu_flow lu_flow_blr1e-8 lu_flow_blr1e-6

Measured (medium model 3, 632 574 unknowns): lu_flow 48.0 s / 2 811 MB, BLR 1e-8 42.8 s / 2 655 MB
(solution 7.4e-7 from the exact LU), BLR 1e-6 43.8 s / 2 494 MB (8.9e-5): not adopted. On the fine mesh run
one variant per process: lu_flow alone reaches 17 GiB RSS (110 s analysis + factorisation), and a second
variant in the same process was OOM-killed on this 24 GiB machine.
"""
from __future__ import annotations

import argparse
import dataclasses
import resource
import time
from pathlib import Path

import netCDF4  # noqa: F401  (before dolfinx)
from mpi4py import MPI
from petsc4py import PETSc

from ureterfsi.mesh import tags
from ureterfsi.config import load_config_files
from ureterfsi.fsi.linear_solvers import flow_lu_options, schur_fieldsplit_options, set_options
from ureterfsi.fsi.problem import MonolithicFSI
from ureterfsi.fsi.submesh import extract
from ureterfsi.mesh.io import load_mesh
from ureterfsi.workflow import paths as results
from ureterfsi.scenes.ureter import ureter_fluid_scene
from ureterfsi.study import oneway
from ureterfsi.study.options import solver_options

ROOT = Path(__file__).resolve().parent.parent

# PETSc options of each variant: the engine's own option sets, AMG on velocity as the alternative measured
VARIANTS = {
    "lu_whole": {"ksp_type": "preonly", "pc_type": "lu", "pc_factor_mat_solver_type": "mumps",
                 "mat_mumps_icntl_7": 5},                              # LU of the whole mixed system (before)
    "lu_flow": flow_lu_options("mumps"),                               # the engine's direct solve
    # MUMPS block low-rank factorisation (ICNTL(35) = 2: BLR factors, used in the solve too) with dropping
    # tolerance CNTL(7): an approximate LU, so Newton would converge linearly at a rate ~ its error
    "lu_flow_blr1e-8": flow_lu_options("mumps") | {"fieldsplit_flow_mat_mumps_icntl_35": 2,
                                                  "fieldsplit_flow_mat_mumps_cntl_7": 1e-8},
    "lu_flow_blr1e-6": flow_lu_options("mumps") | {"fieldsplit_flow_mat_mumps_icntl_35": 2,
                                                  "fieldsplit_flow_mat_mumps_cntl_7": 1e-6},
    "fieldsplit_ilu": {},                                              # linear_solver: fieldsplit
    "fieldsplit_amg": {"fieldsplit_momentum_pc_type": "hypre",
                       "fieldsplit_momentum_pc_hypre_boomeramg_strong_threshold": 0.5},
}


def urine_problem(cfg, model, level, steps):
    dt = cfg["time"]["dt"]
    history = oneway.wall_history(cfg, (steps + 1) * dt, dt)
    mesh, ct, ft = load_mesh(ROOT / results.mesh("quarter", model, level), MPI.COMM_WORLD)
    fluid = extract(mesh, ct, ft, [tags.FLUID])
    u_wall, v_wall = oneway.inner_wall_motion(history, False)
    scene = ureter_fluid_scene(cfg, fluid.mesh, fluid.cell_tags, fluid.facet_tags, u_wall, v_wall, False)
    options = dataclasses.replace(solver_options(cfg), mesh_motion_coupling="segregated")
    pb = MonolithicFSI(scene, options)
    pb.solve_steady(0.0)
    for _ in range(steps):
        pb.step(dt)
    A, b = pb.pose_newton_system(dt)   # the Newton system of the next step at the previous state
    return pb, A, b


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--config", nargs="+", default=[str(ROOT / "config/config.yaml")])
    ap.add_argument("--model", default="3")
    ap.add_argument("--level", default="coarse", help="a quarter mesh under results/meshes (snakemake all_meshes)")
    ap.add_argument("--steps", type=int, default=3, help="time steps before the measured system")
    ap.add_argument("--variants", nargs="+", default=list(VARIANTS), choices=list(VARIANTS))
    args = ap.parse_args()
    cfg = load_config_files(args.config)
    pb, A, b = urine_problem(cfg, args.model, args.level, args.steps)
    print(f"model {args.model}, level {args.level} (quarter): {A.getSize()[0]} unknowns, "
          f"{A.getInfo()['nz_used']:.3e} stored nonzeros, krylov_rtol {cfg['solver']['krylov_rtol']:.0e}")
    print("| variant | set-up + first solve (s) | kept solve (s) | Krylov iterations | LU memory (MB) | max RSS (GiB) "
          "| difference from lu_flow |")
    print("|---|---|---|---|---|---|---|")
    reference = None
    flow_is = pb.layout.field_is({"mirror": ["displacement"], "flow": ["velocity", "pressure"]})
    schur_is = pb.layout.field_is({"momentum": ["velocity", "displacement"], "pressure": ["pressure"]})
    for name in args.variants:
        prefix = f"bench_{name}_"
        opts = VARIANTS[name] if name.startswith("lu") else schur_fieldsplit_options(
            cfg["solver"]["krylov_rtol"], 400) | VARIANTS[name]
        set_options(prefix, opts)
        ksp = PETSc.KSP().create(MPI.COMM_WORLD)
        ksp.setOptionsPrefix(prefix)
        ksp.setOperators(A)
        if name != "lu_whole":
            ksp.getPC().setType("fieldsplit")
            ksp.getPC().setFieldSplitIS(*(flow_is if name.startswith("lu_flow") else schur_is))
        ksp.setFromOptions()
        x = b.duplicate()
        t0 = time.perf_counter()
        ksp.solve(b, x)
        t1 = time.perf_counter()
        ksp.solve(b, x)
        t2 = time.perf_counter()
        lu_mb = "-"
        if name.startswith("lu"):
            pc = ksp.getPC().getFieldSplitSubKSP()[1].getPC() if name.startswith("lu_flow") else ksp.getPC()
            lu_mb = pc.getFactorMatrix().getMumpsInfog(22)
        rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024**2
        its = "-" if name.startswith("lu") else ksp.getIterationNumber()
        if name == "lu_flow":
            reference = x.copy()
        diff = "-" if reference is None else f"{(x - reference).norm() / reference.norm():.1e}"
        print(f"| {name} | {t1 - t0:.2f} | {t2 - t1:.2f} | {its} | {lu_mb} | {rss:.2f} | {diff} |", flush=True)
        if ksp.getConvergedReason() < 0:
            print(f"  {name}: KSP reason {ksp.getConvergedReason()}")
        ksp.destroy()


if __name__ == "__main__":
    main()
