"""Linear solvers of the engine's Newton system: strategies of MonolithicFSI chosen by SolverOptions.linear_solver.

`WholeSystemLU` (a direct package: LU of the whole system), `FlowBlockLU` (a direct package in a fluid-alone
scene: LU of the velocity-pressure block), `SchurFieldsplit` (`fieldsplit`, fluid-alone: GMRES with a Schur
block preconditioner) and, for coupled scenes,

`BlockGaussSeidel` (`SolverOptions.linear_solver: block_gauss_seidel`): GMRES, right-preconditioned by one
block Gauss-Seidel sweep over the splits solid -> mesh -> flow (PETSc PCFIELDSPLIT, multiplicative), with
an LU factorisation (MUMPS, METIS ordering) of each diagonal block:

    P^-1 = lower-block-triangular solve of [[A_SS, 0, 0], [A_MS, A_MM, 0], [A_FS, A_FM, A_FF]],

S the solid split (velocity and displacement dofs of solid cells, interface included; the solid pressure; the
pinned fluid pressures; the Dirichlet rows of the fluid displacement), M the free fluid mesh displacement,
F the fluid-only velocity and pressure (`dofs.DofLayout.coupled_splits`). The upper blocks (fluid traction
on the solid, A_SF, A_SM; the flow's shape derivatives on the mesh, A_MF = 0) are left to GMRES. The
Krylov iteration runs on the current Jacobian, so a kept (older) block factor changes the iteration count,
never the Newton iterate beyond the Krylov tolerance.
"""
from __future__ import annotations

import functools
import gc
import os
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass

from petsc4py import PETSc

SPLITS = ("solid", "mesh", "flow")
KRYLOV = ("block_gauss_seidel",)            # linear_solver values handled here
DIRECT = ("mumps", "superlu_dist", "superlu", "umfpack")
MUMPS_WORKSPACE_PERCENT = 20                # MUMPS's own default ICNTL(14)
OPTIONS_TABLE_SIZE = 512                    # PETSc 3.18's options database: a fixed table per process (MAXOPTIONS)
OWNER_PREFIX = "ureterfsi_"


def owner_prefix(owner: object) -> str:
    """The options prefix of one owner's solvers (a problem's): unique among the live objects."""
    return f"{OWNER_PREFIX}{id(owner)}_"


def set_options(prefix: str, options: dict) -> None:
    """Write `options` under `prefix` into PETSc's options database. Where its fixed table has no room, garbage is
    collected first: problems left in reference cycles still hold theirs until their finalizers (forget_options)
    run; if that frees too little, a RuntimeError says how many live entries hold it."""
    db = PETSc.Options()
    held = db.getAll()
    new = [k for k in options if f"{prefix}{k}" not in held]
    if len(held) + len(new) > OPTIONS_TABLE_SIZE:
        gc.collect()
        held = db.getAll()
        if len(held) + len(new) > OPTIONS_TABLE_SIZE:
            owners = len({k[len(OWNER_PREFIX):].split("_")[0] for k in held if k.startswith(OWNER_PREFIX)})
            raise RuntimeError(f"PETSc's options table is full ({len(held)} of {OPTIONS_TABLE_SIZE} entries, "
                               f"{owners} live problems' solvers among them): {len(new)} more under '{prefix}' "
                               "do not fit; drop the problems no longer needed")
    for key, value in options.items():
        db[f"{prefix}{key}"] = value


def forget_options(prefix: str) -> None:
    """Delete every PETSc option under `prefix` (once the solvers that read them are gone)."""
    if PETSc.Sys.isFinalized():
        return
    opts = PETSc.Options()
    for key in [k for k in opts.getAll() if k.startswith(prefix)]:
        opts.delValue(key)


def direct_package(linear_solver: str) -> str:
    """The LU package of a sub-problem (a mesh-motion or stent solve) under `linear_solver`: the package
    itself, or MUMPS under a Krylov strategy."""
    return linear_solver if linear_solver in DIRECT else "mumps"


@dataclass(frozen=True)
class Mumps:
    """How every MUMPS factorisation of the engine is made (PETSc options under the factor's prefix): METIS
    nested-dissection ordering (ICNTL(7) = 5, which suits 3D meshes), the workspace margin over MUMPS's estimate
    in per cent (ICNTL(14)), and in or out of core (ICNTL(22) = 1: the factors are written to disk as they are
    computed, memory holds the fronts being worked on, and each solve reads the factors back, from the page cache
    while memory allows). The same factors either way."""
    workspace_percent: int = MUMPS_WORKSPACE_PERCENT
    out_of_core: bool = False

    def options(self) -> dict:
        """The PETSc options; out of core, this process's scratch directory is made first (out_of_core_directory)."""
        opts = {"mat_mumps_icntl_7": 5, "mat_mumps_icntl_14": int(self.workspace_percent)}
        if self.out_of_core:
            out_of_core_directory()
            opts["mat_mumps_icntl_22"] = 1
        return opts


# removes a directory once its stdin closes: when the process holding the pipe's other end has ended
REAPER = "import shutil, sys; sys.stdin.buffer.read(); shutil.rmtree(sys.argv[1], ignore_errors=True)"
_reapers: list = []


@functools.cache
def out_of_core_directory() -> str:
    """The directory this process's MUMPS writes out-of-core factors to, made at the first call in $MUMPS_OOC_TMPDIR
    or else the temporary directory (tempfile: $TMPDIR, node-local on most clusters) and set as MUMPS_OOC_TMPDIR
    (MUMPS reads it at each factorisation). A process of its own removes it once this one has ended, however it
    ends: MUMPS deletes a factor's files only when the factor is destroyed, which an exiting process need not do
    and a killed one cannot."""
    path = tempfile.mkdtemp(prefix=f"ureterfsi-mumps-{os.getpid()}-", dir=os.environ.get("MUMPS_OOC_TMPDIR"))
    os.environ["MUMPS_OOC_TMPDIR"] = path
    read, write = os.pipe()           # `write` stays open for this process's life: the kernel closes it at its end
    _reapers.append((write, subprocess.Popen([sys.executable, "-c", REAPER, path], stdin=read,
                                             start_new_session=True)))
    os.close(read)
    return path


def block_gauss_seidel_options(rtol: float, max_iterations: int, mumps: Mumps = Mumps()) -> dict:
    """PETSc options (under the KSP prefix) of BlockGaussSeidel: right-preconditioned GMRES (the residual it
    tests is the true one), multiplicative fieldsplit, MUMPS LU (`mumps`) on every split."""
    opts = {"ksp_type": "gmres", "ksp_gmres_restart": 100, "ksp_pc_side": "right", "ksp_rtol": rtol,
            "ksp_atol": 0.0, "ksp_max_it": max_iterations, "ksp_norm_type": "unpreconditioned",
            "pc_type": "fieldsplit", "pc_fieldsplit_type": "multiplicative"}
    for name in SPLITS:
        opts |= {f"fieldsplit_{name}_ksp_type": "preonly", f"fieldsplit_{name}_pc_type": "lu",
                 f"fieldsplit_{name}_pc_factor_mat_solver_type": "mumps"}
        opts |= {f"fieldsplit_{name}_{k}": v for k, v in mumps.options().items()}
    return opts


def flow_lu_options(package: str, mumps: Mumps = Mumps()) -> dict:
    """PETSc options (under the KSP prefix) of the segregated direct solve: PCFieldSplit additive over the
    splits "mirror" (Jacobi) and "flow" (LU by `package`; `mumps` for MUMPS)."""
    opts = {"ksp_type": "preonly", "pc_type": "fieldsplit", "pc_fieldsplit_type": "additive",
            "fieldsplit_mirror_ksp_type": "preonly", "fieldsplit_mirror_pc_type": "jacobi",
            "fieldsplit_flow_ksp_type": "preonly", "fieldsplit_flow_pc_type": "lu",
            "fieldsplit_flow_pc_factor_mat_solver_type": package}
    if package == "mumps":
        opts |= {f"fieldsplit_flow_{k}": v for k, v in mumps.options().items()}
    return opts


def schur_fieldsplit_options(rtol: float, max_iterations: int) -> dict:
    """PETSc options (under the KSP prefix) of linear_solver "fieldsplit" over the splits "momentum" and
    "pressure": GMRES, lower Schur factorisation with the "selfp" approximation, ILU(0) / BoomerAMG."""
    return {"ksp_type": "gmres", "ksp_gmres_restart": 200, "ksp_pc_side": "right", "ksp_rtol": rtol,
            "ksp_atol": 0.0, "ksp_max_it": max_iterations, "pc_type": "fieldsplit",
            "pc_fieldsplit_type": "schur", "pc_fieldsplit_schur_fact_type": "lower",
            "pc_fieldsplit_schur_precondition": "selfp",
            "fieldsplit_momentum_ksp_type": "preonly", "fieldsplit_momentum_pc_type": "ilu",
            "fieldsplit_pressure_ksp_type": "preonly", "fieldsplit_pressure_pc_type": "hypre"}


class LinearSolver:
    """A strategy for the Newton system A dx = -R of MonolithicFSI, chosen by SolverOptions.linear_solver: it
    sets up `ksp`; `operator_changed()` after each fresh Jacobian, `invalidate()` to refactorise everything at
    the next one, `solve(b, x, rtol)`, `failure_detail()` (why the last solve failed)."""
    sizes = None                          # {split: unknowns} of the block strategies

    def __init__(self, ksp: PETSc.KSP, counters: dict):
        self.ksp, self.counters = ksp, counters

    def operator_changed(self):
        pass

    def invalidate(self):
        pass

    def solve(self, b: PETSc.Vec, x: PETSc.Vec, rtol: float):
        self.ksp.solve(b, x)

    def failure_detail(self) -> str:
        return ""

    def factor_matrix(self):
        raise TypeError(f"linear solver {type(self).__name__} has no single LU factor")


def mumps_status(factor) -> str:
    return (f"; MUMPS INFOG(1) = {factor.getMumpsInfog(1)}, INFOG(2) = {factor.getMumpsInfog(2)} "
            f"(-8/-9/-13: workspace or memory, -10: singular matrix)")


class WholeSystemLU(LinearSolver):
    """LU of the whole Newton system by a direct package (MUMPS with `mumps`)."""

    def __init__(self, ksp: PETSc.KSP, prefix: str, package: str, counters: dict,
                 mumps: Mumps = Mumps()):
        super().__init__(ksp, counters)
        self.package = package
        ksp.setType("preonly")
        pc = ksp.getPC()
        pc.setType("lu")
        pc.setFactorSolverType(package)
        if package == "mumps":
            set_options(prefix, mumps.options())

    def factor_matrix(self):
        return self.ksp.getPC().getFactorMatrix()

    def failure_detail(self) -> str:
        return mumps_status(self.factor_matrix()) if self.package == "mumps" else ""


class FlowBlockLU(LinearSolver):
    """Direct solve of a fluid-alone Newton system. Its Jacobian is block diagonal: the flow (velocity,
    pressure) block and the identity rows of the mirrored mesh displacement, whose columns the flow rows do
    not touch. LU of the flow block alone (PCFieldSplit, additive): even with the matrix's own sparsity
    (sparsity.flow_matrix), MUMPS's analysis of the whole matrix (METIS on the isolated mirror dofs) is slow
    (docs/performance.md, benchmarks/fluid_linear_solver.py)."""

    def __init__(self, ksp: PETSc.KSP, prefix: str, package: str, splits: list, counters: dict,
                 mumps: Mumps = Mumps()):
        super().__init__(ksp, counters)
        self.package = package
        set_options(prefix, flow_lu_options(package, mumps))
        pc = ksp.getPC()
        pc.setType("fieldsplit")
        pc.setFieldSplitIS(*splits)

    def factor_matrix(self):
        return self.ksp.getPC().getFieldSplitSubKSP()[1].getPC().getFactorMatrix()

    def failure_detail(self) -> str:
        return mumps_status(self.factor_matrix()) if self.package == "mumps" else ""


class SchurFieldsplit(LinearSolver):
    """GMRES on the Newton system [[A, -B^T], [B, 0]] of a fluid-alone scene, right-preconditioned by the
    lower block factorisation with the Schur complement S = B A^-1 B^T approximated by B diag(A)^-1 B^T
    (PCFieldSplit "selfp", a SIMPLE-type approximation suited to the mass-dominated A of small time steps;
    Elman, Silvester & Wathen 2014, ch. 9): ILU(0) on A (cheaper here than AMG, whose V-cycles on the P2
    block cost 7x more for the same iteration count: benchmarks/fluid_linear_solver.py), BoomerAMG on
    the Schur approximation. The mirrored mesh-displacement rows (identity) go with the velocity block."""

    def __init__(self, ksp: PETSc.KSP, prefix: str, splits: list, rtol: float, max_iterations: int, counters: dict):
        super().__init__(ksp, counters)
        set_options(prefix, schur_fieldsplit_options(rtol, max_iterations))
        pc = ksp.getPC()
        pc.setType("fieldsplit")
        pc.setFieldSplitIS(*splits)
        counters["krylov_iterations"] = 0

    def solve(self, b: PETSc.Vec, x: PETSc.Vec, rtol: float):
        self.ksp.solve(b, x)
        self.counters["krylov_iterations"] += self.ksp.getIterationNumber()

    def failure_detail(self) -> str:
        return (f" after {self.ksp.getIterationNumber()} Krylov iterations, residual "
                f"{self.ksp.getResidualNorm():.3e} (-3: iteration limit, -5/-9: breakdown/NaN)")


class BlockGaussSeidel(LinearSolver):
    """Block Gauss-Seidel-preconditioned GMRES with kept block factors.

    At every fresh Jacobian the flow block is refactorised; the solid and mesh factors are kept (the mesh
    block, the linear extension operator, does not change at all) until a linear solve needs more than
    `refactorise_iterations` Krylov iterations, after which the next fresh Jacobian refactorises every
    block. `invalidate()` (a failed step, a checkpoint) refactorises every block at the next one.
    `counters` (a dict, updated in place): Krylov iterations and the factorisations of each block, counted from
    the factors' own PETSc object states; `timings` (updated in place): seconds in the extraction of the blocks
    ("block_extraction"), in each block's set-up ("{split}_factorise") and in GMRES ("krylov")."""

    def __init__(self, ksp: PETSc.KSP, prefix: str, splits: dict, rtol: float, max_iterations: int,
                 refactorise_iterations: int, counters: dict, timings: dict, kept=("solid", "mesh"),
                 mumps: Mumps = Mumps()):
        if set(splits) != set(SPLITS) or any(splits[n].getSize() == 0 for n in SPLITS):
            sizes = {n: splits[n].getSize() for n in splits}
            raise ValueError(f"linear_solver 'block_gauss_seidel' needs non-empty splits {SPLITS} (a scene with a "
                             f"fluid and a solid region), got sizes {sizes}; use a direct solver (mumps)")
        unknown = set(kept) - set(SPLITS)
        if unknown:
            raise ValueError(f"BlockGaussSeidel kept blocks must be among {SPLITS}, got {sorted(unknown)}")
        self.ksp, self.kept, self.refactorise_iterations = ksp, tuple(kept), refactorise_iterations
        set_options(prefix, block_gauss_seidel_options(rtol, max_iterations, mumps))
        pc = ksp.getPC()
        pc.setType("fieldsplit")
        pc.setFieldSplitIS(*[(n, splits[n]) for n in SPLITS])
        self.sizes = {n: splits[n].getSize() for n in SPLITS}
        self.counters = counters          # the problem's: incremented in place
        counters |= {"krylov_iterations": 0} | {f"{n}_factorisations": 0 for n in SPLITS}
        self.timings = timings
        timings |= {"block_extraction": 0.0, "krylov": 0.0} | {f"{n}_factorise": 0.0 for n in SPLITS}
        self._refresh = set(SPLITS)       # blocks to refactorise at the next fresh Jacobian
        self._states = None               # PETSc object states of the block factors after the last solve

    def sub_ksps(self) -> dict:
        """{split: its KSP} (after the first solve)."""
        return dict(zip(SPLITS, self.ksp.getPC().getFieldSplitSubKSP()))

    def operator_changed(self):
        """A fresh Jacobian: each block keeps its factor unless it is due for refactorisation."""
        if self._states is not None:
            for name, sub in self.sub_ksps().items():
                sub.getPC().setReusePreconditioner(name not in self._refresh)
        self._refresh = set(SPLITS) - set(self.kept)

    def invalidate(self):
        """Refactorise every block at the next fresh Jacobian."""
        self._refresh = set(SPLITS)

    def solve(self, b: PETSc.Vec, x: PETSc.Vec, rtol: float):
        """x = A^-1 b to GMRES's relative residual rtol."""
        self.ksp.setTolerances(rtol=rtol)
        t0 = time.perf_counter()
        self.ksp.setUp()                  # PCFIELDSPLIT: extracts the blocks of a changed operator
        t1 = time.perf_counter()
        self.timings["block_extraction"] += t1 - t0
        for name, sub in self.sub_ksps().items():
            sub.setUp()                   # LU of a block unless its factor is kept
            t2 = time.perf_counter()
            self.timings[f"{name}_factorise"] += t2 - t1
            t1 = t2
        self.ksp.solve(b, x)
        self.timings["krylov"] += time.perf_counter() - t1
        its = self.ksp.getIterationNumber()
        self.counters["krylov_iterations"] += its
        states = {}
        for name, sub in self.sub_ksps().items():
            factor = sub.getPC().getFactorMatrix()
            states[name] = factor.stateGet()
            if self._states is None or states[name] != self._states[name]:
                self.counters[f"{name}_factorisations"] += 1
        self._states = states
        if its > self.refactorise_iterations:
            self._refresh = set(SPLITS)

    def failure_detail(self) -> str:
        """Why the last solve failed: iterations, residual, and the MUMPS status of every block."""
        detail = (f" after {self.ksp.getIterationNumber()} GMRES iterations, residual "
                  f"{self.ksp.getResidualNorm():.3e} (-3: iteration limit, -11: a block factorisation failed)")
        try:
            infos = {n: sub.getPC().getFactorMatrix().getMumpsInfog(1) for n, sub in self.sub_ksps().items()}
        except PETSc.Error:
            return detail
        return detail + "; MUMPS INFOG(1) per block " + ", ".join(f"{n} {v}" for n, v in infos.items())
