"""Monolithic ALE fluid-structure problem: one Newton system per time step on a conforming mesh.

Fields on the whole mesh (mixed element): velocity v (P2; fluid velocity in the fluid, solid
velocity in the solids), displacement u (P2; solid displacement in the solids, ALE mesh
displacement in the fluid), fluid pressure p (P1; only if the scene has a fluid) and solid pressure
pi (P0; only if it has a Mooney-Rivlin solid). Velocity continuity and traction balance at every
fluid-solid interface follow from the conforming continuous v and u (paper eqs. 22-25).

Rows that belong to no physics are pinned: pressure dofs owned only by solid cells, solid-pressure
dofs outside the Mooney-Rivlin cells. The mesh-motion rows of interface displacement dofs are removed,
so the interface moves exactly with the solid kinematics (no mesh-motion pollution): fsi.constraints.
Time: BDF2 with variable step (Backward Euler for the first step); steady mode switches d/dt off.
Elsewhere: the options (fsi.options), the residual's terms (fsi.forms, fsi.physics), the dofs per field and split
(fsi.dofs), the problem's Newton system and its assembly (fsi.newton_system), Newton's method and its convergence
tests (fsi.newton), the BDF history, predictor and restart state (fsi.history), the linear solvers
(fsi.linear_solvers), the partitioned sweeps (fsi.partitioned), the segregated mesh motion (fsi.mesh_motion), the
matrices' sparsity (fsi.sparsity) and the ALE Jacobian guard (fsi.ale_jacobian).
"""
from __future__ import annotations

import logging
import sys
import weakref

import numpy as np
import ufl
from dolfinx import fem
from dolfinx.fem import petsc as fem_petsc
from petsc4py import PETSc

from . import forms, physics, sparsity
from .ale_jacobian import ALEJacobian
from .constraints import Constraints
from .dofs import DofLayout
from .end_conditions import STEADY_PASSES, EndConditions
from .history import HistoryMethods
from .linearly_implicit import LinearlyImplicitStep
from .linear_solvers import (BlockGaussSeidel, FlowBlockLU, LinearSolver, SchurFieldsplit, WholeSystemLU,
                             forget_options, owner_prefix)
from .materials import MooneyRivlin
from .mesh_motion import MeshMotionMethods, cell_stiffness
from .newton import Newton, NewtonDivergence
from .newton_system import NewtonSystemMethods
from .operators import Operators
from .options import SolverOptions
from .block_forms import partitioned_coupling
from .partitioned import PartitionedCoupling
from .release import collect_garbage, destroy_held
from .scene import Scene

log = logging.getLogger("ureterfsi.fsi")


class MonolithicFSI(NewtonSystemMethods, HistoryMethods, MeshMotionMethods):
    """The problem of a `scene` solved with `options`: its mixed space, state and BDF history, forms, constraints
    and solver strategies; `step(dt)` advances it, `solve_steady()` poses a steady state."""

    def __init__(self, scene: Scene, options: SolverOptions | None = None):
        self.scene = scene
        self.options = opts = options or SolverOptions()
        mesh = scene.mesh
        self.mesh = mesh
        self.comm = mesh.comm
        self.ops = ops = Operators(mesh, scene.axisymmetric)
        cell = mesh.ufl_cell()

        fluid_tags = tuple(scene.fluid.tags) if scene.fluid else ()
        mr_tags = tuple(t for s in scene.solids if isinstance(s.material, MooneyRivlin) for t in s.tags)
        solid_tags = tuple(t for s in scene.solids for t in s.tags)
        self.fluid_tags, self.solid_tags = fluid_tags, solid_tags
        self.segregated = opts.mesh_motion_coupling == "segregated"
        lumped = any(ob.condition is not None for ob in scene.open_boundaries)
        if lumped and opts.urine_step != "newton":
            raise ValueError("an open boundary's lumped condition (Waveform, Compartment, Valve) needs urine_step "
                             "'newton' (the linearly implicit step does not carry its Jacobian term)")
        opts.check(bool(fluid_tags), bool(solid_tags), scene.mesh_motion is not None)

        # --- mixed space --------------------------------------------------------------------
        elements = {"velocity": ufl.VectorElement("Lagrange", cell, opts.velocity_degree),
                    "displacement": ufl.VectorElement("Lagrange", cell, opts.velocity_degree)}
        if fluid_tags:
            elements["pressure"] = ufl.FiniteElement("Lagrange", cell, opts.pressure_degree)
        if mr_tags:
            elements["solid_pressure"] = ufl.FiniteElement("DG", cell, 0)
        self.field_names = list(elements)
        self.W = W = fem.FunctionSpace(mesh, ufl.MixedElement(list(elements.values())))
        self.index = {name: i for i, name in enumerate(self.field_names)}
        self.unknowns = W.dofmap.index_map.size_global * W.dofmap.index_map_bs
        self.layout = DofLayout(W, self.field_names)

        self.x = fem.Function(W, name="state")
        self.x_n = fem.Function(W)
        self.x_nm1 = fem.Function(W)
        self._x_nm2 = np.zeros_like(self.x_nm1.x.array)   # x_nm1 of the last accepted step
        # b1 x_n + b2 x_nm1, the history's part of the BDF derivative: the forms' one history coefficient (each
        # mixed-space coefficient costs every assembly its packing and evaluation); kept by _sync_history
        self.history = fem.Function(W, name="bdf_history")
        self.x_dot = fem.Function(W, name="time_derivative")   # BDF d/dt of the last accepted step
        self.t = fem.Constant(mesh, 0.0)
        self.dt = fem.Constant(mesh, 1.0)
        self.bdf = [fem.Constant(mesh, 0.0) for _ in range(3)]   # d/dt a = (b0 a + b1 a_n + b2 a_nm1)/dt
        b0 = self.bdf[0]
        self.time = 0.0
        self.dt_prev = None
        self.dt_prev2 = None       # the step before dt_prev (quadratic predictor)

        X, H = self.split(self.x), self.split(self.history)
        tests = self.split(ufl.TestFunction(W))
        v, u = X["velocity"], X["displacement"]
        phi, psi = tests["velocity"], tests["displacement"]

        def ddt(name, current=None):
            """(b0 a + b1 a_n + b2 a_nm1) / dt of field `name`, a = `current` (default: the state's)."""
            return (b0 * (X[name] if current is None else current) + H[name]) / self.dt

        dvdt, dudt = ddt("velocity"), ddt("displacement")
        if self.segregated:
            # the mesh displacement is a known coefficient of the step: the fluid rows do not depend on
            # the displacement unknowns, which mirror it through a Dirichlet condition on every dof
            self.mesh_space, self._mesh_dofs = self.sub("displacement").collapse()
            self.mesh_displacement = fem.Function(self.mesh_space, name="mesh_displacement")
            u = self.mesh_displacement
            dudt = ddt("displacement", u)
        md = {"quadrature_degree": opts.quadrature_degree}
        self.dx = dx = ufl.Measure("dx", domain=mesh, subdomain_data=scene.cell_tags, metadata=md)
        self.ds = ds = ufl.Measure("ds", domain=mesh, subdomain_data=scene.facet_tags, metadata=md)

        # --- residual -----------------------------------------------------------------------
        self.end_conditions = ends = EndConditions(self, v, u, dudt, phi)

        def terms(dx, ds=ds, convecting=None):
            return forms.residual_terms(ops, scene, X, tests, dvdt, dudt, self.t, dx, ds, convecting,
                                        ends.normal_stress)

        whole = terms(dx)
        R = whole.urine + whole.solids + whole.loads
        self.residual_form = fem.form(R)
        self.jacobian_form = fem.form(ufl.derivative(R, self.x))

        self.mesh_form = self.mesh_jacobian_form = None
        if fluid_tags:
            self.stiffness = cell_stiffness(mesh, self.cells(fluid_tags), opts.mesh_stiffening)
        if fluid_tags and not self.segregated:
            Rm = physics.mesh_motion_residual(ops, opts.mesh_motion, u, psi, self.stiffness, dx(fluid_tags),
                                              opts.mesh_jacobian_stiffening)
            self.mesh_form = fem.form(Rm)
            self.mesh_jacobian_form = fem.form(ufl.derivative(Rm, self.x))

        # --- constraints --------------------------------------------------------------------
        # PETSc options of this problem's solvers live under one prefix, removed when the problem goes (the
        # options database holds at most 512 entries per process)
        self.options_prefix = owner_prefix(self)
        weakref.finalize(self, forget_options, self.options_prefix).atexit = False
        self.counters = {"factorisations": 0, "reused_solves": 0}
        self.timings = {"assemble_residual": 0.0, "assemble_jacobian": 0.0, "factorise": 0.0, "solve": 0.0,
                        "mesh_motion": 0.0}
        others = tuple(t for t in fluid_tags + solid_tags if t not in mr_tags)
        self.constraints = Constraints(self.layout, scene.dirichlet, scene.facet_tags,
                                       self.cells(fluid_tags) if fluid_tags else None,
                                       self.cells(solid_tags) if solid_tags else None,
                                       self.cells(others) if mr_tags else None,
                                       (self.mesh_displacement, self._mesh_dofs) if self.segregated else None)
        self.bcs = self.constraints.bcs
        if self.segregated:
            self._setup_mesh_motion()

        # --- algebra ------------------------------------------------------------------------
        own = opts.jacobian_sparsity == "couplings"
        solids = self.solid_regions()
        self._A = None
        self.b = fem_petsc.create_vector(self.residual_form)
        self._b_free = self.b.duplicate()
        self._reaction_ready = False    # _b_free holds the residual of the last accepted state (assemble_reaction)
        if self.mesh_form is not None:
            self.Am = (sparsity.coupled_matrix(W, self.field_names, self.cells(fluid_tags), solids, part="mesh")
                       if own else fem_petsc.create_matrix(self.mesh_jacobian_form))
            self._mesh_jacobian_ready = False
            self.bm = fem_petsc.create_vector(self.mesh_form)
        self.dx_vec = self.x.vector.duplicate()
        self.nonlinear_solver = Newton(opts, self.x, self.dx_vec, self.layout.field_owned, self.comm)
        self.ksp = PETSc.KSP().create(self.comm)
        prefix = self.options_prefix
        self.ksp.setOptionsPrefix(prefix)
        if opts.coupling_scheme == "monolithic":
            self.ksp.setOperators(self.A)
        self.linear_solver = self._linear_solver(prefix)
        self.ksp.setFromOptions()
        self.partitioned = self._partitioned(whole, terms) if opts.coupling_scheme == "partitioned" else None
        self._jacobian_valid = False
        # det(I + Grad u) at the fluid cells' vertices: the inversion guard
        self.ale_jacobian = ALEJacobian(ops, u, self.cells(fluid_tags)) if fluid_tags else None
        self.linearly_implicit = (LinearlyImplicitStep(self, terms) if opts.urine_step == "linearly_implicit"
                                  else None)

    closed = False

    def close(self) -> None:
        """Destroy the problem's PETSc objects (matrices, vectors, KSPs and their LU factors, index sets: those of its
        solver strategies and mesh motion included; not its scene's), those Python has dropped on its communicator,
        and its PETSc options; the problem is unusable after. Collective. Also on leaving a `with` block."""
        if self.closed:
            return
        self.closed = True
        destroy_held(self, keep=(self.scene,))
        forget_options(self.options_prefix)
        collect_garbage(self.comm)

    def __enter__(self) -> MonolithicFSI:
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def __del__(self):
        # one process closes a dropped problem here; on several, close() it (destruction is collective, Python's
        # collection is not): see fsi.release. Not while the interpreter shuts down (a problem still held when a
        # failed solve exits): petsc4py can no longer reach MPI then, and the process's end frees everything
        if getattr(self, "options_prefix", None) and self.comm.size == 1 and not sys.is_finalizing():
            self.close()

    # ---------------------------------------------------------------------------------------
    @property
    def A(self) -> PETSc.Mat:
        """The whole Newton system's matrix, made at its first use (the partitioned scheme's condensed wall and
        urine blocks assemble their own)."""
        if self._A is None:
            if self.segregated:
                self._A = sparsity.flow_matrix(self.W, self.field_names)
            elif self.options.jacobian_sparsity == "couplings":
                self._A = sparsity.coupled_matrix(self.W, self.field_names, self.cells(self.fluid_tags),
                                                  self.solid_regions())
            else:
                self._A = fem_petsc.create_matrix(self.jacobian_form)
        return self._A

    def solid_regions(self) -> list:
        """[(local cells, Mooney-Rivlin?)] per solid region of the scene."""
        return [(self.cells(tuple(s.tags)), isinstance(s.material, MooneyRivlin)) for s in self.scene.solids]

    def sub(self, name):
        return self.layout.sub(name)

    def split(self, which=None):
        """UFL parts {field name: expression} of the current state (or of `which`, e.g. x_dot)."""
        parts = ufl.split(which or self.x)
        return {name: parts[i] for i, name in enumerate(self.field_names)}

    def fill(self, name, value: float):
        """Set every dof of one field of the current state to a constant (an initial guess: Newton then
        applies the constraints, e.g. the pinned pressure dofs of solid cells)."""
        _, dofs = self.sub(name).collapse()
        self.x.x.array[np.asarray(dofs)] = value
        self._reaction_ready = False

    def field(self, name, which=None):
        """Collapsed copy of a field of the current (or given) state."""
        f = (which or self.x).sub(self.index[name]).collapse()
        f.name = name
        return f

    def cells(self, tags) -> np.ndarray:
        """Sorted local cells (owned and ghost) of the given cell tags."""
        ct = self.scene.cell_tags
        return np.unique(np.concatenate([ct.find(t) for t in tags] or [np.zeros(0, np.int32)])).astype(np.int32)

    def _linear_solver(self, prefix) -> LinearSolver:
        """The strategy of SolverOptions.linear_solver: GMRES + Schur fieldsplit or LU of the flow block
        (fluid-alone, segregated), block Gauss-Seidel GMRES (coupled), or LU of the whole system."""
        o = self.options
        if o.linear_solver == "fieldsplit":
            splits = self.layout.field_is({"momentum": [f for f in self.field_names if f != "pressure"],
                                           "pressure": ["pressure"]})
            return SchurFieldsplit(self.ksp, prefix, splits, o.krylov_rtol, o.krylov_max_iterations, self.counters)
        if o.linear_solver == "block_gauss_seidel":
            splits = self.layout.coupled_splits(self.cells(self.solid_tags), self.constraints.pins,
                                                self.constraints.dirichlet)
            return BlockGaussSeidel(self.ksp, prefix, self.layout.split_is(splits), o.krylov_rtol,
                                    o.krylov_max_iterations, o.krylov_refactorise_iterations, self.counters,
                                    self.timings, mumps=o.mumps())
        if self.segregated:
            splits = self.layout.field_is({"mirror": ["displacement"],
                                           "flow": [f for f in self.field_names if f != "displacement"]})
            return FlowBlockLU(self.ksp, prefix, o.linear_solver, splits, self.counters, o.mumps())
        return WholeSystemLU(self.ksp, prefix, o.linear_solver, self.counters, o.mumps())

    def _partitioned(self, whole: forms.ResidualTerms, terms) -> PartitionedCoupling:
        """The partitioned strategy (fsi.block_forms.partitioned_coupling) on the residual's terms `whole` and
        `terms`(dx, ds), the same terms with other measures."""
        return partitioned_coupling(self, whole, terms)

    def factor_matrix(self):
        """The PETSc factor of the (flow block of the) Jacobian, for solver diagnostics."""
        return self.linear_solver.factor_matrix()

    # ---------------------------------------------------------------------------------------
    def step(self, dt):
        """Advance from self.time by dt. On failure the state is restored and NewtonDivergence raised."""
        self.set_bdf(dt)
        t_new = self.time + dt
        self.t.value = t_new
        self.constraints.update(t_new)
        if self.segregated:
            self.solve_mesh_motion()
        if self.linearly_implicit is not None:
            self.linearly_implicit.extrapolate(dt)
        guesses = [self.options.predictor] + (["constant"] if self.options.predictor != "constant" else [])
        for k, guess in enumerate(guesses):
            self._predict(guess, dt)
            try:
                its, history = self.newton()
                break
            except NewtonDivergence as err:
                self.invalidate_jacobian()
                if k + 1 < len(guesses):
                    # an extrapolation over large or abrupt steps can overshoot: the previous state first,
                    # before the integrator halves the step
                    log.info("Newton failed from the %s predictor (%s); retrying from the previous state", guess, err)
                    continue
                self.x.x.array[:] = self.x_n.x.array
                self.t.value = self.time
                raise
        self.x_dot.x.array[:] = self.time_derivative()
        self.end_conditions.accept()            # before the history moves on (its face fluxes' w is the step's)
        self._x_nm2[:] = self.x_nm1.x.array     # the step's own history, for assemble_reaction
        self.x_nm1.x.array[:] = self.x_n.x.array
        self.x_n.x.array[:] = self.x.x.array
        self._sync_history()
        self.dt_prev2, self.dt_prev, self.time = self.dt_prev, dt, t_new
        self._reaction_ready = True     # Newton's last residual was assembled at the accepted state
        collect_garbage(self.comm)      # the step's temporary PETSc objects (fsi.release)
        return its, history


    def solve_steady(self, t=None):
        """Steady state (d/dt switched off) at time t: e.g. fluid at rest under the reference pressure,
        or a steady FSI benchmark. The result becomes the initial state of a transient run."""
        if t is not None:
            self.time = t
        for const in self.bdf:
            const.value = 0.0
        self._sync_history()
        self.t.value = self.time
        self.constraints.update(self.time)
        if self.segregated:
            self.solve_mesh_motion()
        its, history = self.newton()
        self.end_conditions.hold()
        for _ in range(STEADY_PASSES - 1 if self.end_conditions.compartments else 0):
            more, history = self.newton()     # a compartment's next pseudo-step (fsi.end_conditions)
            its += more
            self.end_conditions.hold()
        self.x_n.x.array[:] = self.x.x.array
        self.x_nm1.x.array[:] = self.x.x.array
        self._x_nm2[:] = self.x.x.array
        self.x_dot.x.array[:] = 0.0
        self._reaction_ready = True
        return its, history

    def assemble_reaction(self, vec) -> None:
        """Residual of the last accepted step (or steady solve) without boundary conditions, into vec
        (ghosts summed): at a Dirichlet dof the consistent reaction, the force the constraint exerts on
        the system; elsewhere zero to the Newton tolerance. The step's time derivative is restored for the
        assembly (after a step x_n, x_nm1 already hold the next step's history). Right after a step it is
        Newton's last residual evaluation, kept before the constraints were applied: no assembly."""
        if self._reaction_ready:
            self._b_free.copy(vec)
            return
        shifted = self.x_n.x.array.copy(), self.x_nm1.x.array.copy()
        self.x_n.x.array[:], self.x_nm1.x.array[:] = shifted[1], self._x_nm2
        self._sync_history()
        try:
            with vec.localForm() as loc:
                loc.set(0.0)
            fem_petsc.assemble_vector(vec, self.residual_form)
            vec.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
        finally:
            self.x_n.x.array[:], self.x_nm1.x.array[:] = shifted
            self._sync_history()
