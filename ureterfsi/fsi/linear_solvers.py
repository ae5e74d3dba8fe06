"""Krylov linear solvers of the coupled (monolithic ALE) Newton system.

`BlockGaussSeidel` (`SolverOptions.linear_solver: block_gauss_seidel`): GMRES, right-preconditioned by one
block Gauss-Seidel sweep over the splits solid -> mesh -> flow (PETSc PCFIELDSPLIT, multiplicative), with
an LU factorisation (MUMPS, METIS ordering) of each diagonal block:

    P^-1 = lower-block-triangular solve of [[A_SS, 0, 0], [A_MS, A_MM, 0], [A_FS, A_FM, A_FF]],

S the solid split (velocity and displacement dofs of solid cells, interface included; the solid pressure; the
pinned fluid pressures; the Dirichlet rows of the fluid displacement), M the free fluid mesh displacement,
F the fluid-only velocity and pressure (`MonolithicFSI.coupled_splits`). The upper blocks (fluid traction
on the solid, A_SF, A_SM; the flow's shape derivatives on the mesh, A_MF = 0) are left to GMRES. The
Krylov iteration runs on the current Jacobian, so a kept (older) block factor changes the iteration count,
never the Newton iterate beyond the Krylov tolerance.
"""
from __future__ import annotations

import time

from petsc4py import PETSc

SPLITS = ("solid", "mesh", "flow")
KRYLOV = ("block_gauss_seidel",)            # linear_solver values handled here
DIRECT = ("mumps", "superlu_dist", "superlu", "umfpack")


def direct_package(linear_solver: str) -> str:
    """The LU package of a sub-problem (a mesh-motion or stent solve) under `linear_solver`: the package
    itself, or MUMPS under a Krylov strategy."""
    return linear_solver if linear_solver in DIRECT else "mumps"


def block_gauss_seidel_options(rtol: float, max_iterations: int) -> dict:
    """PETSc options (under the KSP prefix) of BlockGaussSeidel: right-preconditioned GMRES (the residual it
    tests is the true one), multiplicative fieldsplit, MUMPS LU with METIS ordering on every split."""
    opts = {"ksp_type": "gmres", "ksp_gmres_restart": 100, "ksp_pc_side": "right", "ksp_rtol": rtol,
            "ksp_atol": 0.0, "ksp_max_it": max_iterations, "ksp_norm_type": "unpreconditioned",
            "pc_type": "fieldsplit", "pc_fieldsplit_type": "multiplicative"}
    for name in SPLITS:
        opts |= {f"fieldsplit_{name}_ksp_type": "preonly", f"fieldsplit_{name}_pc_type": "lu",
                 f"fieldsplit_{name}_pc_factor_mat_solver_type": "mumps",
                 f"fieldsplit_{name}_mat_mumps_icntl_7": 5}
    return opts


class BlockGaussSeidel:
    """Block Gauss-Seidel-preconditioned GMRES with kept block factors.

    At every fresh Jacobian the flow block is refactorised; the solid and mesh factors are kept (the mesh
    block, the linear extension operator, does not change at all) until a linear solve needs more than
    `refactorise_iterations` Krylov iterations, after which the next fresh Jacobian refactorises every
    block. `invalidate()` (a failed step, a checkpoint) refactorises every block at the next one.
    `counters` (a dict, updated in place): Krylov iterations and the factorisations of each block, counted from
    the factors' own PETSc object states; `timings` (updated in place): seconds in the extraction of the blocks
    ("block_extraction"), in each block's set-up ("{split}_factorise") and in GMRES ("krylov")."""

    def __init__(self, ksp: PETSc.KSP, prefix: str, splits: dict, rtol: float, max_iterations: int,
                 refactorise_iterations: int, counters: dict, timings: dict, kept=("solid", "mesh")):
        if set(splits) != set(SPLITS) or any(splits[n].getSize() == 0 for n in SPLITS):
            sizes = {n: splits[n].getSize() for n in splits}
            raise ValueError(f"linear_solver 'block_gauss_seidel' needs non-empty splits {SPLITS} (a scene with a "
                             f"fluid and a solid region), got sizes {sizes}; use a direct solver (mumps)")
        unknown = set(kept) - set(SPLITS)
        if unknown:
            raise ValueError(f"BlockGaussSeidel kept blocks must be among {SPLITS}, got {sorted(unknown)}")
        self.ksp, self.kept, self.refactorise_iterations = ksp, tuple(kept), refactorise_iterations
        o = PETSc.Options()
        for key, value in block_gauss_seidel_options(rtol, max_iterations).items():
            o[f"{prefix}{key}"] = value
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
