"""Partitioned solution of the monolithic FSI residual (SolverOptions.coupling_scheme "partitioned").

The same discrete problem as Newton on the whole system, R(x) = 0, solved by nonlinear block Gauss-Seidel sweeps
over the splits of dofs.DofLayout.coupled_splits (S solid with the interface velocity, M free fluid mesh
displacement, F fluid velocity and pressure):

    x_S <- x_S - A_SS^-1 R_S(x)      repeated (modified Newton on the solid rows; mesh and flow held),
    x_M <- x_M - A_MM^-1 R_M(x)      once (the mesh extension is linear in x_M),
    x_F <- x_F - A_FF^-1 R_F(x)      repeated (the urine in the mesh just moved),

a Dirichlet-Neumann iteration: the wall moves the urine's boundary, the urine's traction loads the wall in the
next sweep. A step has converged (sweep_convergence "contraction") when the a posteriori bound of a contraction,

    ||G(x_k) - x*|| <= rho / (1 - rho) ||G(x_k) - x_k||,

x* = G(x*) the step's solution, G one sweep, rho its contraction (the largest secant ratio
||G(x_j) - G(x_j-1)|| / ||x_j - x_j-1|| of this step's sweeps and of the previous step's), is within newton_field_rtol
in the max norm relative to each field (where rho >= 1, so that only Anderson's mixing converges the sweeps, by the
residual test below); or ("residual") when the residual test of Newton holds and no field changed over the last
sweep by more than newton_field_rtol of its max norm. Each block's LU (MUMPS) is kept across iterations and steps
and refreshed when its iteration contracts by less than block_reuse_contraction or when the sweeps a stale LU costs
outweigh a refresh (block_refresh_sweeps, RefreshSchedule): A_SS from the whole Jacobian, A_MM the
fixed extension operator (factorised once), A_FF from the derivative of the flow rows in the velocity and pressure
directions only (exactly the Jacobian's flow block, a third of its assembly cost). Lumped end conditions
(fsi.end_conditions) as in Newton's solve: their face pressures evaluated from the current iterate before each
block's rows, their rank-k Jacobian term applied on the flow block's kept LU by the Woodbury identity (its
restriction to the flow rows and columns; the wall's LU, whose rows meet the end faces only at their rims, keeps
its block without it: its updates, not the fixed point, are the poorer). Why it pays: the coupling is
weak (the sweeps contract by ~3e-3 on the ureter) while Newton on the whole system applies every block's factor
in each Krylov iteration of each Newton iteration (docs/performance.md). This module makes the sweeps and the blocks'
solves; when an LU is refreshed, how the sweeps are mixed and when they stop is fsi.sweep_policy's.
"""
from __future__ import annotations

import logging
import math
import time
from dataclasses import dataclass

import numpy as np
from dolfinx import fem
from dolfinx.fem import petsc as fem_petsc
from mpi4py import MPI
from petsc4py import PETSc

from . import forms
from .block_factors import BlockFactor, ComponentFactor
from .block_jacobian import BlockJacobian
from .condensation import CondensedSolidFactor, kinematic_pairs, mass_eigenvalue_floor
from .linear_solvers import SPLITS
from .newton import NewtonDivergence, fields_off, measure_field_increments
from .sweep_policy import RefreshSchedule, SweepPolicyMethods, stale_factor

# the order of a sweep: the wall first (it drives the flow), then the mesh it moves, then the urine
ORDER = SPLITS

log = logging.getLogger("ureterfsi.fsi")


@dataclass
class BlockForms:
    """A block's rows (`residual`), their Jacobian in the block's directions (`jacobian`) and its matrix on W
    (assembled for the first refresh only, then freed); the same Jacobian on the block's own fields (`direct`,
    fsi.block_jacobian: every later refresh); the wall's also the solids' mass form and its matrix (`mass`)."""
    residual: fem.Form
    jacobian: fem.Form
    matrix: PETSc.Mat | None
    direct: BlockJacobian
    mass: tuple | None = None


class PartitionedCoupling(SweepPolicyMethods):
    """The sweeps of the module docstring on `problem` (a MonolithicFSI of a coupled scene, monolithic mesh
    motion) over its coupled `splits`. `flow`: the urine's rows (every term of the residual but the solids' volume
    terms) and their Jacobian in the velocity and pressure directions; `wall` (None: the whole Jacobian's block):
    the wall's rows (the residual over the solid cells and the urine cells touching them) and their Jacobian along
    the kinematic direction, for the condensed LU (fsi.condensation).
    `solve()` replaces the problem's Newton solve: returns (sweeps, residual norms at each sweep's start and
    the last); counters (in problem.counters): sweeps, block solves and factorisations per split;
    timings (problem.timings): each block's factorisation and solves, the block Jacobians' and rows' assembly."""

    def __init__(self, problem, splits: dict, flow: BlockForms, wall: BlockForms | None, block_iterations: int):
        self.pb = pb = problem
        self.forms = {"flow": flow, "solid": wall}
        self.block_iterations = int(block_iterations)
        if any(pb.comm.allreduce(len(splits[n])) == 0 for n in ORDER):
            sizes = {n: pb.comm.allreduce(len(splits[n])) for n in ORDER}
            raise ValueError(f"coupling_scheme 'partitioned' needs non-empty splits {ORDER} (a scene with a fluid and "
                             f"a solid region), got sizes {sizes}")
        self.index = pb.layout.split_is(splits)
        self.splits = splits                    # {name: owned local dofs}: a block's entries, gathered by numpy
        self.sizes = {n: self.index[n].getSize() for n in ORDER}
        prefix, mumps = pb.options_prefix, pb.options.mumps()
        self.factors = {n: BlockFactor(pb.comm, f"{prefix}partitioned_{n}_", mumps) for n in ORDER}
        self.factors["mesh"] = ComponentFactor(pb.comm, f"{prefix}partitioned_mesh_", mumps, [
            np.searchsorted(splits["mesh"], np.intersect1d(splits["mesh"], dofs))
            for dofs in pb.layout.components_owned("displacement")])
        self.condensed = wall is not None
        if self.condensed:
            v_pos, u_pos, mismatched = kinematic_pairs(pb, splits["solid"])
            if pb.comm.allreduce(mismatched):
                raise ValueError(f"solid_block 'condensed': {pb.comm.allreduce(mismatched)} solid nodes constrain the "
                                 f"velocity or the displacement but not both (use solid_block 'whole')")
            mass_form, mass = wall.mass
            fem_petsc.assemble_matrix(mass, mass_form)
            mass.assemble()
            pressure = pb.layout.field_owned.get("solid_pressure", np.zeros(0, np.int32))     # P0: cell unknowns
            self.factors["solid"] = CondensedSolidFactor(
                pb.comm, f"{prefix}partitioned_solid_", mumps, splits["solid"], pb.layout.offset, v_pos, u_pos, mass,
                mass_eigenvalue_floor(pb, pb.cells(pb.solid_tags)),
                cell_pos=np.searchsorted(splits["solid"], np.intersect1d(splits["solid"], pressure)))
            mass.destroy()
        # {split: {field: positions in the split's local array}} for the per-field increments of a block
        self.positions = {n: {f: np.searchsorted(splits[n], np.intersect1d(splits[n], d))
                              for f, d in pb.layout.field_owned.items()} for n in ORDER}
        # the rows a block's iteration needs, assembled alone: the urine's and (condensed) the wall's from their
        # forms, the mesh's from the (linear) mesh-motion form; else the wall's from the whole residual
        self._row_vectors = {"flow": pb.b.duplicate(), "mesh": pb.bm.duplicate()}
        if self.condensed:
            self._row_vectors["solid"] = pb.b.duplicate()
        # a block's increment and rows in its own layout (VecGetSubVector would build a scatter at every call)
        self.work = {n: PETSc.Vec().createMPI((len(splits[n]), PETSc.DECIDE), comm=pb.comm) for n in ORDER}
        self.rows = {n: self.work[n].duplicate() for n in ORDER}
        self.field_increments = {}      # {field: (||dx_f||_inf, ||x_f||_inf)} of the last sweep's change
        self.kept = []                          # Anderson's differences (dx, dG) kept from earlier steps, newest first
        self.kept_rate = math.nan               # and the b0/dt they were made at
        self.contraction = 0.0                  # the sweeps' contraction estimate of the last step (error_bound)
        self.schedule = RefreshSchedule(pb.options.block_refresh_sweeps)
        pb.counters |= ({"sweeps": 0, "scheduled_refreshes": 0}
                        | {f"{n}_solves": 0 for n in ORDER}
                        | {f"{n}_factorisations": 0 for n in ORDER})
        pb.timings |= {f"{n}_factorise": 0.0 for n in ORDER} | {f"{n}_solve": 0.0 for n in ORDER}
        pb.timings |= {"assemble_flow_jacobian": 0.0, "assemble_solid_jacobian": 0.0, "assemble_block_rows": 0.0,
                       "kinematic_check": 0.0}

    def invalidate(self) -> None:
        """Refactorise the solid and flow blocks at their next use (the mesh block is a fixed operator) and forget
        the mixing's differences and the contraction estimate of earlier steps."""
        for n in ("solid", "flow"):
            self.factors[n].rate = None
        self.schedule.reset()
        self.kept = []
        self.contraction = 0.0

    # ---------------------------------------------------------------------------------------
    def refresh(self, name: str) -> None:
        """Refactorise block `name` from a Jacobian at the current state: the urine's and (condensed) the wall's
        from their own forms, the mesh's from the fixed mesh-motion operator, else the whole Jacobian's block."""
        pb = self.pb
        t0 = time.perf_counter()
        rate = pb._rate()
        if name == "solid":
            kept = self.factors[name].rate
            if kept is not None and not math.isclose(kept, rate, rel_tol=1e-12):
                self.schedule.reset()                   # another b0/dt: another operator, another floor
            self.schedule.wall_refreshed()
        forms, factor = self.forms.get(name), self.factors[name]
        direct = forms is not None and forms.direct.operator is not None
        matrix = forms.direct.assemble() if direct else self._matrix_on_W(name)
        if forms is not None:
            pb.timings[f"assemble_{name}_jacobian"] += time.perf_counter() - t0
        t1 = time.perf_counter()
        if direct:
            factor.factorise(matrix, rate)
        else:
            factor.refresh(matrix, self.index[name], rate)
            if forms is not None:
                self.bind_direct(name)
        if name == "flow" and pb.end_conditions:
            pb.end_conditions.factorised(self._flow_solve, self.splits["flow"])
        pb.timings[f"{name}_factorise"] += time.perf_counter() - t1
        pb.counters[f"{name}_factorisations"] += 1
        if pb.counters[f"{name}_factorisations"] == 1:        # the set-up's progress: the first LUs are its longest
            log.info("%s block: %d unknowns, first Jacobian and LU in %.1f s", name, self.sizes[name], time.perf_counter() - t0)

    def _flow_solve(self, rhs: PETSc.Vec, out: PETSc.Vec) -> None:
        """out = A_FF^-1 rhs by the flow block's kept LU (the end conditions' Woodbury term)."""
        failed = self.factors["flow"].solve(rhs, out)
        if failed:
            self.invalidate()
            raise NewtonDivergence(f"flow block: {failed}", [])

    def _matrix_on_W(self, name: str) -> PETSc.Mat:
        """The Jacobian on W whose block `name` is factorised: the block's own form (the urine's, the condensed
        wall's), the fixed mesh-motion operator, or the whole Jacobian."""
        pb, forms = self.pb, self.forms.get(name)
        if forms is not None:
            forms.matrix.zeroEntries()
            fem_petsc.assemble_matrix(forms.matrix, forms.jacobian, bcs=pb.bcs)
            forms.matrix.assemble()
            return forms.matrix
        if name == "mesh":
            return pb.mesh_motion_matrix()
        pb._assemble_jacobian()
        return pb.A

    def bind_direct(self, name: str) -> None:
        """After the first refresh of block `name` from its Jacobian on W: its later ones assemble the block's own
        Jacobian (fsi.block_jacobian) straight into the operator just extracted, checked here against it; the
        matrix on W is freed."""
        pb, forms, factor = self.pb, self.forms[name], self.factors[name]
        split = self.splits[name]
        if name == "solid":
            operator, rows, cols = factor.operator, factor.q_pos, factor.r_pos
        else:
            operator, rows = factor.block, np.arange(len(split))
            cols = rows
        forms.direct.bind(pb, operator, split, rows, cols, pb.constraints.constrained)
        forms.direct.check(name)
        if forms.matrix is not None:
            forms.matrix.destroy()
            forms.matrix = None

    def _current(self, name: str) -> bool:
        rate = self.factors[name].rate
        if rate is None:
            return False
        return name == "mesh" or math.isclose(rate, self.pb._rate(), rel_tol=1e-12)

    def _scales(self) -> dict:
        """{field: ||x_f||_inf} of the current state, reduced over the ranks."""
        x = self.pb.x.x.array
        return {f: s for f, (s, _) in measure_field_increments(x, x, self.pb.layout.field_owned, self.pb.comm).items()}

    def block_residual(self, name: str) -> PETSc.Vec:
        """A vector whose entries on split `name` are the residual's at the current state."""
        pb = self.pb
        if name == "solid" and not self.condensed:
            pb._assemble_residual()
            return pb.b
        t0 = time.perf_counter()
        if name != "mesh" and pb.end_conditions:
            pb.end_conditions.update()      # the face pressures of the current iterate (the mesh rows have none)
        vec = self._row_vectors[name]
        if name == "mesh":
            pb.assemble_mesh_rows(vec)
        else:
            with vec.localForm() as loc:
                loc.set(0.0)
            fem_petsc.assemble_vector(vec, self.forms[name].residual)
            vec.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
            fem_petsc.set_bc(vec, pb.bcs, pb.x.vector, -1.0)
        pb.timings["assemble_block_rows"] += time.perf_counter() - t0
        return vec

    def _block(self, name: str, scale: dict, assembled: bool) -> None:
        """Modified Newton on the rows of split `name` from the current state (at most block_iterations updates, one
        for the linear mesh block); `assembled`: the whole residual at the current state is in problem.b."""
        pb, o = self.pb, self.pb.options
        dofs, dx, rb = self.splits[name], self.work[name], self.rows[name]
        iterations = 1 if name == "mesh" else self.block_iterations
        previous = None
        for k in range(iterations):
            vec = pb.b if assembled else self.block_residual(name)
            assembled = False
            rb.array[:] = vec.array_r[dofs]
            norm = rb.norm()
            if not math.isfinite(norm):
                raise NewtonDivergence(f"non-finite residual in the {name} block", [norm])
            if not self._current(name) or stale_factor(norm, previous, o) or not o.reuse_jacobian:
                self.refresh(name)
            t0 = time.perf_counter()
            failed = self.factors[name].solve(rb, dx)
            if failed:
                self.invalidate()
                raise NewtonDivergence(f"{name} block: {failed}", [norm])
            if name == "flow" and pb.end_conditions:
                pb.end_conditions.correct(dx)
            pb.timings[f"{name}_solve"] += time.perf_counter() - t0
            pb.counters[f"{name}_solves"] += 1
            pb.x.x.array[dofs] -= dx.array_r
            pb.x.x.scatter_forward()
            previous = norm
            increments = measure_field_increments(dx.array_r, dx.array_r, self.positions[name], pb.comm)
            if not fields_off({f: (i, scale[f]) for f, (i, _) in increments.items()}, scale,
                              o.newton_field_rtol or o.newton_stol, o.newton_increment_floor):
                break


    def match_kinematics(self) -> None:
        """Set the paired solid velocities to the BDF derivative of their displacements, v_i = du_i/dt
        (problem.time_derivative; v_i = 0 in a steady solve): the kinematic rows' nodal solution, which an
        extrapolated guess breaks, done before a step's first assembly. The condensed wall solve cannot restore these
        rows, and the residual norm hardly sees them (M ~ the wall's volume), but the sweeps keep them: a condensed
        solve does, and Anderson's mixing is G(x_k) plus differences of sweeps made at the same b0/dt (kept ones are
        forgotten at another), which solve the homogeneous rows b0 du = dt dv whatever their step's history. An
        accepted state whose rows do not hold is refused (_check_accepted)."""
        pb, factor = self.pb, self.factors["solid"]
        solid = self.splits["solid"]
        pb.x.x.array[solid[factor.v_pos]] = pb.time_derivative(solid[factor.u_pos])
        pb.x.x.scatter_forward()

    def kinematic_defect(self, rows: PETSc.Vec | None = None) -> float:
        """max |M^-1 r_U| of the residual in `rows` (the whole residual in problem.b by default, or the wall's rows):
        how far the solids' kinematic rows, which no condensed wall solve restores, are from holding (m/s); or its
        bound ||r_U||_2 / lambda_min(M) (the factor's mass_floor) where that is within newton_increment_floor (the
        sweeps keep the rows to round-off: then no Cholesky solve). Timed (timings kinematic_check)."""
        pb, factor = self.pb, self.factors["solid"]
        t0 = time.perf_counter()
        rb = (pb.b if rows is None else rows).array_r[self.splits["solid"]]
        defect = math.inf
        if factor.mass_floor > 0.0:
            r_u = rb[factor.u_pos]
            defect = math.sqrt(pb.comm.allreduce(float(r_u @ r_u))) / factor.mass_floor
        if defect > pb.options.newton_increment_floor:
            y = factor.kinematic_correction(rb)
            defect = pb.comm.allreduce(float(np.abs(y).max(initial=0.0)), op=MPI.MAX)
        pb.timings["kinematic_check"] += time.perf_counter() - t0
        return defect


    def solve(self):
        """Solve R(x) = 0 for the current step by sweeps, Anderson-mixed over the last anderson_depth of them
        (and the differences of the last anderson_reuse steps' sweeps). Returns (sweeps, residual norms: the
        step's first and, under "residual", each test's; the accepted state's last)."""
        pb, o = self.pb, self.pb.options
        self.field_increments, self.bound, self.step_contraction = {}, math.inf, 0.0
        if self.condensed:
            self.match_kinematics()
        r = r0 = pb._assemble_residual()
        if not math.isfinite(r):
            raise NewtonDivergence("non-finite residual at the step's start", [r])
        history = [r]
        n = pb.x.vector.getLocalSize()                  # owned entries of the state
        xs, gs = [], []                                 # the sweeps' starts and results: the mixing's and the bound's
        if not math.isclose(self.kept_rate, pb._rate(), rel_tol=1e-12):     # another b0/dt: another fixed point
            self.kept, self.kept_rate = [], pb._rate()
        assembled = True                                # problem.b holds the whole residual at the current state
        for sweep in range(o.newton_max_iterations):
            before = pb.x.x.array[:n].copy()
            scale = self._scales()
            for k, name in enumerate(ORDER):
                self._block(name, scale, assembled=assembled and k == 0)
            pb.counters["sweeps"] += 1
            xs.append(before)
            gs.append(pb.x.x.array[:n].copy())
            del xs[:-(max(o.anderson_depth, 1) + 1)], gs[:-(max(o.anderson_depth, 1) + 1)]
            self.field_increments = measure_field_increments(before - gs[-1], gs[-1], pb.layout.field_owned, pb.comm)
            done, assembled, mixed = self.converged(xs, gs, r0, history)
            if done:
                if not assembled:
                    history.append(pb._assemble_residual())     # the accepted state's: the record, the reaction
                self._check_accepted(history[-1], sweep + 1, history)
                self.contraction = self.step_contraction
                self._keep(xs, gs)
                due = self.schedule.converged(sweep + 1)
                for block in due:
                    self.factors[block].rate = None         # refreshed at the next step's first use
                pb.counters["scheduled_refreshes"] += bool(due)
                return sweep + 1, history
            if not mixed and self.mix(xs, gs):
                assembled = False
        self.invalidate()
        off = ", ".join(f"{f} {v:.1e}" for f, v in self._fields_off(o.newton_field_rtol).items())
        bound = f"; error bound {self.bound:.1e}" if o.sweep_convergence == "contraction" else ""
        raise NewtonDivergence(f"no convergence in {o.newton_max_iterations} block Gauss-Seidel sweeps"
                               + (f" (last change relative to the field: {off}{bound})" if off or bound else ""),
                               history)
