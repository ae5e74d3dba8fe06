"""The partitioned coupling scheme (SolverOptions.coupling_scheme "partitioned", ureterfsi.fsi.partitioned): block
Gauss-Seidel sweeps solid -> mesh -> flow with Anderson mixing solve the monolithic residual, so they reach the same
discrete solution as Newton on the whole system. Verified on the axisymmetric Mooney-Rivlin tube (a strongly
coupled case: plain sweeps contract by ~0.6 each) against a tightly converged full Newton."""
from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest
import ufl
from dolfinx import fem
from dolfinx import mesh as dmesh
from dolfinx.fem import petsc as fem_petsc
from mpi4py import MPI
from petsc4py import PETSc

from helpers.engine_cases import (WALL_ENDS, FailingFactorisation, field_errors, tube_case, tube_problem, tube_reference,
                           tube_run)
from ureterfsi.fsi import MonolithicFSI, NewtonDivergence, SolverOptions, sparsity
from ureterfsi.fsi.condensation import CondensedSolidFactor, mass_eigenvalue_floor
from ureterfsi.fsi.operators import Operators
from ureterfsi.fsi.block_factors import BlockFactor
from ureterfsi.fsi.linear_solvers import Mumps
from ureterfsi.fsi.block_jacobian import BlockJacobian, field_components, field_space
from ureterfsi.fsi.block_forms import direct_jacobian, direction

TOL = dict(linear_solver="mumps", newton_rtol=1e-8, newton_atol=1e-10, reuse_jacobian=True)


@pytest.fixture(scope="module")
def reference():
    with tube_reference() as pb:
        yield pb


@pytest.mark.parametrize("field_rtol", [1e-6, 1e-8])
@pytest.mark.parametrize("block_iterations", [1, 3])
def test_partitioned_reaches_the_monolithic_solution(reference, field_rtol, block_iterations):
    pb, sweeps = tube_run(coupling_scheme="partitioned", newton_field_rtol=field_rtol,
                          block_iterations=block_iterations, **TOL)
    errors = field_errors(pb, reference)
    assert max(errors.values()) <= field_rtol, errors
    assert max(sweeps) <= 8, sweeps
    c = pb.counters
    assert c["mesh_factorisations"] == 1 and c["solid_factorisations"] <= 4, c    # the block factors are kept
    assert c["solid_solves"] <= block_iterations * c["sweeps"], c


def test_anderson_mixing_is_what_converges_the_strongly_coupled_tube(reference):
    """Plain Dirichlet-Neumann sweeps on the tube contract by ~0.6 (the urine's added mass on a soft wall): ~30
    sweeps a step; Anderson mixing over 5 sweeps needs 6."""
    plain, sweeps_plain = tube_run(coupling_scheme="partitioned", newton_field_rtol=1e-6, anderson_depth=0,
                                   newton_max_iterations=60, sweep_convergence="residual", **TOL)
    mixed, sweeps_mixed = tube_run(coupling_scheme="partitioned", newton_field_rtol=1e-6,
                                   sweep_convergence="residual", **TOL)
    assert sum(sweeps_plain) >= 3 * sum(sweeps_mixed), (sweeps_plain, sweeps_mixed)
    assert max(field_errors(plain, reference).values()) <= 1e-6


def test_the_flow_block_jacobian_is_the_jacobians_flow_block():
    """The cheaper flow-only form (derivative in the velocity and pressure directions) assembles exactly the flow
    block of the whole Jacobian."""
    pb, _ = tube_problem(options=SolverOptions(coupling_scheme="partitioned", **TOL))
    pb.solve_steady()
    pb.set_bdf(2e-3)
    rng = np.random.default_rng(1)
    pb.x.x.array[:] += 1e-6 * rng.standard_normal(pb.x.x.array.size)
    pb.x.x.scatter_forward()
    A, _ = pb.pose_newton_system(2e-3)
    flow = pb.partitioned.index["flow"]
    whole = A.createSubMatrix(flow, flow)
    pb.partitioned.refresh("flow")
    block = pb.partitioned.factors["flow"].block
    diff = whole.copy()
    diff.axpy(-1.0, block, structure=PETSc.Mat.Structure.DIFFERENT_NONZERO_PATTERN)
    assert diff.norm() <= 1e-12 * whole.norm()


def test_the_block_rows_are_the_residuals_rows():
    """The urine's rows from their own form and the mesh's from the mesh-motion form are the whole residual's."""
    pb, _ = tube_problem(options=SolverOptions(coupling_scheme="partitioned", **TOL))
    pb.solve_steady()
    pb.set_bdf(2e-3)
    pb.t.value = 2e-3
    rng = np.random.default_rng(2)
    pb.x.x.array[:] += 1e-6 * rng.standard_normal(pb.x.x.array.size)
    pb.x.x.scatter_forward()
    _, b = pb.pose_newton_system(2e-3)
    part = pb.partitioned
    for name in ("flow", "mesh"):
        rows, index = part.block_residual(name), part.index[name]
        whole = b.getSubVector(index).array.copy()
        assert np.abs(rows.getSubVector(index).array - whole).max() <= 1e-12 * np.abs(whole).max(), name


@pytest.mark.parametrize("mesh_motion", ["harmonic", "elastic"])
def test_the_mesh_rows_by_the_kept_operator_are_the_forms(mesh_motion):
    """A linear extension's rows are its kept matrix times the state (problem.assemble_mesh_rows): the assembled
    form's rows, the removed rows 0, at a perturbed state."""
    pb, _ = tube_problem(options=SolverOptions(coupling_scheme="partitioned", mesh_motion=mesh_motion, **TOL))
    rng = np.random.default_rng(3)
    pb.x.x.array[:] += 1e-4 * rng.standard_normal(pb.x.x.array.size)
    pb.x.x.scatter_forward()
    rows = pb.bm.duplicate()
    pb.assemble_mesh_rows(rows)
    form = fem_petsc.assemble_vector(pb.mesh_form)
    form.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
    form.array[pb.constraints.mesh_rows_local] = 0.0
    assert np.abs(form.array).max() > 0.0
    assert np.abs(rows.array_r - form.array_r).max() <= 1e-12 * np.abs(form.array_r).max()


@pytest.mark.parametrize("mesh_motion, decoupled", [("harmonic", True), ("elastic", False)])
def test_the_mesh_block_is_factorised_per_component_where_it_does_not_couple_them(mesh_motion, decoupled):
    """The harmonic extension (r-z too: the hoop term is u_r's alone) leaves the displacement's components
    uncoupled: one LU per component; the elastic one couples them: the whole block's LU. Either solves the mesh
    block as its whole LU does, to round-off."""
    pb, _ = tube_problem(options=SolverOptions(coupling_scheme="partitioned", mesh_motion=mesh_motion, **TOL))
    part = pb.partitioned
    part.refresh("mesh")
    factor = part.factors["mesh"]
    assert factor.decoupled is decoupled
    whole = BlockFactor(pb.comm, "test_mesh_whole_", Mumps(100))
    whole.refresh(pb.mesh_motion_matrix(), part.index["mesh"], 0.0)
    b = part.rows["mesh"].duplicate()
    b.setRandom()
    x, y = b.duplicate(), b.duplicate()
    assert factor.solve(b, x) == "" and whole.solve(b, y) == ""
    y.axpy(-1.0, x)
    assert y.norm() <= 1e-12 * x.norm()


def test_a_step_that_does_not_converge_names_the_fields():
    pb, _ = tube_problem(options=SolverOptions(coupling_scheme="partitioned", newton_field_rtol=1e-12,
                                               newton_max_iterations=2, **TOL))
    pb.solve_steady()
    with pytest.raises(NewtonDivergence, match=r"no convergence in 2 block Gauss-Seidel sweeps \(last change "
                                               r"relative to the field: velocity \d"):
        pb.step(2e-3)


def test_partitioned_needs_a_coupled_scene():
    case = tube_case()
    fluid_alone = case.scene
    fluid_alone.solids = []
    with pytest.raises(ValueError, match="coupling_scheme 'partitioned' splits a coupled scene"):
        MonolithicFSI(fluid_alone, SolverOptions(coupling_scheme="partitioned"))
    with pytest.raises(ValueError, match="coupling_scheme 'monolithic' or 'partitioned', got 'staggered'"):
        MonolithicFSI(tube_case().scene, SolverOptions(coupling_scheme="staggered"))


def _tube_newton_system(seed):
    """The tube's Newton system at a perturbed state of its first step: (problem, A, b)."""
    pb, _ = tube_problem(options=SolverOptions(coupling_scheme="partitioned", **TOL))
    pb.solve_steady()
    pb.set_bdf(2e-3)
    pb.t.value = 2e-3
    rng = np.random.default_rng(seed)
    pb.x.x.array[:] += 1e-6 * rng.standard_normal(pb.x.x.array.size)
    pb.x.x.scatter_forward()
    A, b = pb.pose_newton_system(2e-3)
    return pb, A, b


def _on_W(pb, name: str) -> PETSc.Mat:
    """Block `name`'s Jacobian form on the mixed space, assembled at the current state with the conditions into
    the whole Jacobian's pattern (which holds every diagonal: the constrained dofs' identities)."""
    A = sparsity.coupled_matrix(pb.W, pb.field_names, pb.cells(pb.fluid_tags), pb.solid_regions())
    fem_petsc.assemble_matrix(A, pb.partitioned.forms[name].jacobian, bcs=pb.bcs)
    A.assemble()
    return A


def _block_of(pb, name: str, A: PETSc.Mat) -> PETSc.Mat:
    """The block `name` factorises, taken out of A on W: J[Q, R] for the condensed wall, J[F, F] for the urine."""
    part = pb.partitioned
    if name == "solid":
        factor = part.factors["solid"]
        return A.createSubMatrix(factor.IQ, factor.IR)
    return A.createSubMatrix(part.index[name], part.index[name])


@pytest.mark.parametrize("name", ["solid", "flow"])
def test_a_block_jacobian_on_its_own_fields_is_its_block_on_the_mixed_space(name):
    """The wall's and the urine's Jacobians posed on their own fields and assembled straight into their operators
    (fsi.block_jacobian: 31 x 31 and 34 x 34 entries a cell instead of W's 65 x 65 in 3D) are, entry for entry,
    the blocks the factors took out of the Jacobian on W: at a state away from the one of the first refresh, and
    with the constrained dofs' identities. A wrong dof map is refused by the first refresh's check."""
    pb, _, _ = _tube_newton_system(6)
    part = pb.partitioned
    part.refresh(name)                                    # the first: from W, then bound and checked
    direct = part.forms[name].direct
    assert direct.operator is not None and part.forms[name].matrix is None
    rows, cols = (V.dofmap.index_map.size_global for V in direct.form.function_spaces)
    assert rows + cols < 2 * pb.unknowns
    rng = np.random.default_rng(7)
    pb.x.x.array[:] += 1e-5 * rng.standard_normal(pb.x.x.array.size)
    pb.x.x.scatter_forward()
    expected = _block_of(pb, name, _on_W(pb, name))
    assert len(direct.identity[0]) > 0                    # the tube's constrained dofs in the block
    part.refresh(name)                                    # a later refresh: assembled on the block's fields
    got = direct.operator.copy()
    got.axpy(-1.0, expected)
    assert got.norm() <= 1e-13 * expected.norm(), (got.norm(), expected.norm())

    # a wrong dof map (the test dofs shifted by one) is refused: the operator holds the block's values now
    part.forms[name].direct = BlockJacobian(direct.form, np.roll(direct.row_to_W, 1), direct.col_to_W)
    with pytest.raises(RuntimeError, match=f"the {name} block's Jacobian on its own fields"):
        part.bind_direct(name)


def test_the_condensed_solid_solve_is_the_whole_blocks():
    """Eliminating the paired solid velocities through the kinematic rows is exact: for a right-hand side whose
    kinematic rows vanish (as the sweeps keep them) the condensed LU's correction is the whole block's LU's, and
    the kinematic correction makes a state's kinematic rows vanish."""
    pb, A, b = _tube_newton_system(3)
    part = pb.partitioned
    condensed = part.factors["solid"]
    assert isinstance(condensed, CondensedSolidFactor)
    part.refresh("solid")                     # the condensed operator from its own form at this state
    index = part.index["solid"]
    whole = BlockFactor(pb.comm, "test_whole_solid_", Mumps(50))
    whole.refresh(A, index, condensed.rate)
    rhs = b.getSubVector(index).duplicate()
    values = np.random.default_rng(4).standard_normal(rhs.getLocalSize())
    values[condensed.u_pos] = 0.0
    rhs.setArray(values)
    x_whole, x_condensed = rhs.duplicate(), rhs.duplicate()
    assert whole.solve(rhs, x_whole) == "" and condensed.solve(rhs, x_condensed) == ""
    assert np.abs(x_condensed.array - x_whole.array).max() <= 1e-9 * np.abs(x_whole.array).max()
    sizes = condensed.sizes                   # the solid pressure (P0) eliminated cell by cell too
    assert sizes["paired velocities"] > 0 and sizes["cell unknowns"] > 0, sizes
    assert sum(sizes.values()) == part.sizes["solid"], sizes
    # the state's kinematic rows, broken by the perturbation, hold after the correction v_V += M^-1 r_U
    split = part.splits["solid"]
    before = np.abs(b.array_r[split][condensed.u_pos]).max()
    pb.x.x.array[split[condensed.v_pos]] += condensed.kinematic_correction(b.array_r[split])
    pb.x.x.scatter_forward()
    after = np.abs(part.block_residual("solid").array_r[split][condensed.u_pos]).max()
    assert after <= 1e-10 * before, (before, after)


def _smallest_eigenvalue(mat: PETSc.Mat) -> float:
    dense = mat.convert("dense").getDenseArray()
    return float(np.linalg.eigvalsh(0.5 * (dense + dense.T)).min())


def test_the_mass_eigenvalue_floor_is_below_the_smallest_eigenvalue():
    """The element-wise bound of the kinematic mass matrix's smallest eigenvalue (which lets an accepted state's
    kinematic check skip its Cholesky solve) is below the true one and not far: on the tube's solids (r-z, weight
    2 pi r) and on a distorted P2 tetrahedral mesh (3D, weight 1), against dense eigenvalues."""
    pb, _ = tube_problem(options=SolverOptions(coupling_scheme="partitioned"))
    factor = pb.partitioned.factors["solid"]
    true = _smallest_eigenvalue(factor.M)
    assert 0.1 * true <= factor.mass_floor <= true, (factor.mass_floor, true)

    cube = dmesh.create_unit_cube(MPI.COMM_SELF, 2, 2, 2)
    rng = np.random.default_rng(0)
    cube.geometry.x[:, :3] += 0.1 * rng.uniform(-1.0, 1.0, cube.geometry.x[:, :3].shape)
    V = fem.FunctionSpace(cube, ("Lagrange", 2))
    mass = fem_petsc.assemble_matrix(fem.form(ufl.TrialFunction(V) * ufl.TestFunction(V) * ufl.dx))
    mass.assemble()
    true = _smallest_eigenvalue(mass)
    cells = np.arange(cube.topology.index_map(3).size_local, dtype=np.int32)
    problem = SimpleNamespace(mesh=cube, options=SolverOptions(), ops=Operators(cube), comm=MPI.COMM_SELF)
    floor = mass_eigenvalue_floor(problem, cells)
    assert 0.05 * true <= floor <= true, (floor, true)


def test_the_condensation_checks_the_kinematic_pairing():
    """A wall Jacobian whose kinematic rows do not cancel along dv = (b0/dt) du is refused, not condensed."""
    pb, _, _ = _tube_newton_system(5)
    part = pb.partitioned
    condensed = part.factors["solid"]
    part.refresh("solid")
    matrix = _on_W(pb, "solid")
    condensed.check_kinematic_rows(matrix, condensed.rate)
    B = matrix.copy()
    row = int(condensed.IU.getIndices()[0])
    col = int(condensed.IR.getIndices()[condensed.paired_in_r[0]])
    B.setValue(row, col, 1e-3 * condensed.rate * condensed.M.norm())
    B.assemble()
    with pytest.raises(RuntimeError, match="do not cancel along"):
        condensed.check_kinematic_rows(B, condensed.rate)


def test_a_solid_node_constraining_one_of_velocity_and_displacement_is_not_condensed():
    case = tube_case()
    case.scene.dirichlet = [bc for bc in case.scene.dirichlet
                            if not (bc.field == "velocity" and bc.tags == [WALL_ENDS])]
    with pytest.raises(ValueError, match="constrain the velocity or the displacement but not both"):
        MonolithicFSI(case.scene, SolverOptions(coupling_scheme="partitioned", **TOL))
    MonolithicFSI(case.scene, SolverOptions(coupling_scheme="partitioned", solid_block="whole", **TOL))


def test_a_failed_block_factorisation_names_the_block_and_mumps_status():
    """A block LU that fails ends the sweeps with the block's name, PETSc's reason and MUMPS's INFOG codes."""
    pb, _ = tube_problem(options=SolverOptions(coupling_scheme="partitioned", **TOL))

    factor = pb.partitioned.factors["flow"]
    factor.ksp = FailingFactorisation(factor.ksp)
    with pytest.raises(NewtonDivergence, match=r"flow block: LU failed \(PETSc KSP reason -11; MUMPS INFOG\(1\) = "):
        pb.solve_steady()


@pytest.fixture(scope="module")
def reference_8_steps():
    with tube_run(linear_solver="mumps", reuse_jacobian=False, newton_rtol=1e-12, newton_atol=1e-20,
                  newton_stol=1e-13, newton_max_iterations=40, steps=8)[0] as pb:
        yield pb


def test_mixing_with_earlier_steps_differences_saves_sweeps(reference_8_steps):
    """IQN-ILS with reuse on the strongly coupled tube: the differences of the last 2 steps' sweeps in the mixing
    (anderson_reuse 2; forgotten when b0/dt changes, e.g. at the switch from BDF1 to BDF2) give the same solution
    in ~20 % fewer sweeps."""
    runs = {reuse: tube_run(coupling_scheme="partitioned", newton_field_rtol=1e-6, anderson_reuse=reuse, steps=8,
                            **TOL) for reuse in (0, 2)}
    for reuse, (pb, _) in runs.items():
        assert max(field_errors(pb, reference_8_steps).values()) <= 1e-6, reuse
    sweeps = {reuse: sum(s) for reuse, (_, s) in runs.items()}
    assert sweeps[2] <= 0.85 * sweeps[0], sweeps


def test_a_state_whose_kinematic_rows_do_not_hold_is_refused(monkeypatch):
    """The condensed wall solve keeps the kinematic rows but cannot restore them, and the residual test hardly
    sees them: from the extrapolated guess with its velocities left as extrapolated (rows broken), the sweeps reach a
    fixed point that breaks them, refused at acceptance whatever the stop; the rows are checked once a step (and the
    steady solve), not before each wall solve."""
    from ureterfsi.fsi.partitioned import PartitionedCoupling

    calls = []
    defect = PartitionedCoupling.kinematic_defect
    monkeypatch.setattr(PartitionedCoupling, "kinematic_defect", lambda self: calls.append(1) or defect(self))
    pb, _ = tube_run(coupling_scheme="partitioned", newton_field_rtol=1e-6, steps=8, **TOL)
    assert len(calls) == 9, (len(calls), pb.counters)
    assert pb.counters["solid_solves"] > 2 * len(calls), pb.counters
    monkeypatch.setattr(PartitionedCoupling, "match_kinematics", lambda self: None)
    for stop in ("residual", "contraction"):
        with pytest.raises(NewtonDivergence, match="kinematic rows"):
            tube_run(coupling_scheme="partitioned", newton_field_rtol=1e-6, sweep_convergence=stop, steps=8, **TOL)


@pytest.mark.parametrize("anderson_depth", [0, 5])
def test_the_contraction_stop_bounds_each_fields_distance_from_the_steps_solution(anderson_depth):
    """sweep_convergence "contraction" stops when rho / (1 - rho) ||G(x_k) - x_k|| <= newton_field_rtol: the accepted
    state is within newton_field_rtol (relative to each field) of the step's own solution - here the same step
    swept to a tight residual - on the strongly coupled tube (plain sweeps contract by ~0.6, the hard case for the
    estimate), in no more sweeps than the residual test asks for (fewer with plain sweeps)."""
    pb, _ = tube_run(coupling_scheme="partitioned", newton_field_rtol=1e-6, anderson_depth=anderson_depth,
                     newton_max_iterations=80, steps=3, **TOL)
    start, dt = pb.state(), 2e-3
    sweeps = {}
    for stop in ("contraction", "residual"):
        pb.set_state(start)
        pb.partitioned.invalidate()
        pb.options.sweep_convergence = stop
        sweeps[stop] = pb.step(dt)[0]
        if stop == "contraction":
            accepted, bound = pb.x.x.array.copy(), pb.partitioned.bound
    pb.set_state(start)
    pb.options.newton_rtol, pb.options.newton_field_rtol = 1e-13, 1e-11
    pb.step(dt)
    for f in pb.field_names:
        dofs = np.asarray(pb.sub(f).collapse()[1])
        distance = np.abs(accepted[dofs] - pb.x.x.array[dofs]).max() / np.abs(pb.x.x.array[dofs]).max()
        assert distance <= 1e-6, (f, distance, bound)
    assert bound <= 1e-6
    assert sweeps["contraction"] <= sweeps["residual"] - (anderson_depth == 0), sweeps


def test_without_a_contraction_the_stop_is_newtons_residual_test():
    """Sweeps whose secant ratio is >= 1 (only the mixing converges them) give no error bound: the contraction stop
    then asks Newton's residual test, so a state that is the solution is accepted and one that is not is not."""
    pb, _ = tube_problem(options=SolverOptions(coupling_scheme="partitioned", newton_field_rtol=1e-6,
                                               anderson_depth=0, **TOL))
    pb.solve_steady()
    part, n = pb.partitioned, pb.x.vector.getLocalSize()
    x = pb.x.x.array[:n].copy()
    step = 1e-3                                              # m, m/s, Pa: far from the state at rest
    xs, gs = [x - step, x], [x + step, x + 4 * step]        # ||dG|| = 3 ||dx||
    assert part.error_bound(xs, gs) == np.inf
    part.field_increments = {f: (0.0, 1.0) for f in pb.field_names}     # the last sweep changed nothing
    r0 = 1e3 * pb.b.norm()
    # the solution: the residual test holds (assembled, no mixing to make)
    assert part.converged(xs, gs, r0, history=[]) == (True, True, False)
    pb.x.x.array[:n] += step
    pb.x.x.scatter_forward()
    assert part.converged(xs, gs, r0, history=[]) == (False, True, False)
    assert part.error_bound(xs, [x, x]) == 0.0                          # a fixed point: nothing left to bound


def test_the_residual_test_is_made_on_the_mixing():
    """Sweeps of an affine contraction G(y) = x* + (y - x*)/2 along one direction: G(x_k) = x* + d/4 fails the
    residual test, Anderson's mixing of the two sweeps is x* (a secant step is exact on such a G): the test is made
    there and holds, the state is the mixing and problem.b holds its residual."""
    pb, _ = tube_problem(options=SolverOptions(coupling_scheme="partitioned", newton_field_rtol=1e-6, **TOL))
    pb.solve_steady()
    part, n = pb.partitioned, pb.x.vector.getLocalSize()
    x = pb.x.x.array[:n].copy()
    d = 1e-3 * np.random.default_rng(4).standard_normal(n)
    xs, gs = [x + d, x + d / 2], [x + d / 2, x + d / 4]
    part.field_increments = {f: (0.0, 1.0) for f in pb.field_names}
    r0 = 1e3 * pb.b.norm()
    pb.x.x.array[:n] = gs[-1]
    pb.x.x.scatter_forward()
    assert part.converged(xs, gs, r0, history=[]) == (True, True, True)
    assert np.abs(pb.x.x.array[:n] - x).max() <= 1e-9 * np.abs(d).max()
    flow = part.splits["flow"]
    rows = part.block_residual("flow").array_r[flow]
    assert np.abs(pb.b.array_r[flow] - rows).max() <= 1e-12 * np.abs(rows).max()


def test_a_residual_within_the_absolute_tolerance_does_not_make_a_factor_stale():
    """A block whose update left round-off (on the 50 mm ureter ~5e-14 -> ~4e-14) is not stale, whatever the ratio;
    above newton_atol the contraction decides."""
    from ureterfsi.fsi.sweep_policy import stale_factor

    o = SolverOptions(newton_atol=1e-10, block_reuse_contraction=0.5)
    assert not stale_factor(4.1e-14, 5.3e-14, o)
    assert not stale_factor(1e-10, 1e-10, o)
    assert stale_factor(3e-10, 5e-10, o) and stale_factor(2e-3, 3e-3, o)
    assert not stale_factor(1e-3, 3e-3, o) and not stale_factor(1.0, None, o)


def test_the_refresh_schedule_buys_the_wall_lu_once_the_extra_sweeps_cost_as_much():
    """Rent or buy (block_refresh_sweeps): the sweeps beyond a fresh step's are summed; at the limit the wall's LU is
    due, the urine's with it only when no step since the wall's refresh came down to the floor; 0 switches it off.
    The sequences are the 50 mm ureter's (docs/performance.md)."""
    from ureterfsi.fsi.sweep_policy import RefreshSchedule

    s = RefreshSchedule(limit=4)
    assert [s.converged(n) for n in (2, 2, 3, 3)] == [(), (), (), ()]
    assert s.converged(4) == ("solid",)              # 0 + 0 + 1 + 1 + 2 extra sweeps
    s.wall_refreshed()
    assert [s.converged(n) for n in (3, 3, 3)] == [(), (), ()]
    assert s.converged(3) == ("solid", "flow")       # no step came down to 2: the urine's LU is stale too
    s.wall_refreshed()
    assert s.converged(3) == () and s.floor == 3     # the step after both refreshes sets the floor anew
    s.reset()
    assert s.floor is None and s.extra == 0
    off = RefreshSchedule(limit=0)
    assert all(off.converged(n) == () for n in (2, 9, 9, 9))


def test_lus_due_on_schedule_are_refreshed_at_the_next_step_and_keep_the_solution(reference_8_steps, monkeypatch):
    """The tube's sweeps do not grow with its LUs' age (its coupling sets them), so the schedule is forced: with both
    LUs due after every step each step refactorises both once, and the solution is the same."""
    from ureterfsi.fsi.sweep_policy import RefreshSchedule

    plain, _ = tube_run(coupling_scheme="partitioned", newton_field_rtol=1e-6, steps=8, **TOL)
    monkeypatch.setattr(RefreshSchedule, "converged", lambda self, sweeps: ("solid", "flow"))
    pb, _ = tube_run(coupling_scheme="partitioned", newton_field_rtol=1e-6, steps=8, **TOL)
    assert max(field_errors(pb, reference_8_steps).values()) <= 1e-6
    c, p = pb.counters, plain.counters
    assert c["scheduled_refreshes"] == 9, c                       # the steady solve and 8 steps
    assert c["solid_factorisations"] >= 9 > p["solid_factorisations"], (c, p)
    assert c["flow_factorisations"] >= 9 > p["flow_factorisations"], (c, p)


def test_a_step_starts_with_the_kinematic_rows_holding(reference_8_steps, monkeypatch):
    """The paired solid velocities set to the BDF derivative of the extrapolated displacements solve the kinematic
    rows nodally: at every step's start |M^-1 r_U| is round-off (the velocity's scale here ~1e-2 m/s)."""
    from ureterfsi.fsi.partitioned import PartitionedCoupling

    defects = []
    match = PartitionedCoupling.match_kinematics

    def matched(self):
        match(self)
        defects.append(self.kinematic_defect(self.block_residual("solid")))

    monkeypatch.setattr(PartitionedCoupling, "match_kinematics", matched)
    pb, _ = tube_run(coupling_scheme="partitioned", newton_field_rtol=1e-6, steps=8, **TOL)
    assert len(defects) == 9 and max(defects) <= 1e-14, defects
    assert max(field_errors(pb, reference_8_steps).values()) <= 1e-6


def test_a_cheaper_wall_jacobian_keeps_the_solution(reference):
    """wall_jacobian_quadrature_degree integrates the wall's kept Jacobian with its own rule: another matrix (the
    Mooney-Rivlin wall's entries move), the same rows, so the same fixed point within the tolerance."""
    matrices = {}
    for degree in (None, 2):
        pb, _ = tube_problem(options=SolverOptions(coupling_scheme="partitioned", wall_jacobian_quadrature_degree=degree,
                                                   **TOL))
        pb.solve_steady()
        matrices[degree] = _on_W(pb, "solid")
    matrices[2].axpy(-1.0, matrices[None])
    change = matrices[2].norm() / matrices[None].norm()
    assert 1e-8 < change < 0.1, change
    pb, sweeps = tube_run(coupling_scheme="partitioned", newton_field_rtol=1e-6, wall_jacobian_quadrature_degree=2,
                          **TOL)
    assert max(field_errors(pb, reference).values()) <= 1e-6
    assert max(sweeps) <= 8, sweeps
    with pytest.raises(ValueError, match="wall_jacobian_quadrature_degree"):
        tube_problem(options=SolverOptions(coupling_scheme="partitioned", wall_jacobian_quadrature_degree=0, **TOL))


@pytest.mark.parametrize("names", [["displacement"], ["velocity", "pressure"]])
def test_a_field_space_maps_its_dofs_to_the_mixed_spaces(names):
    """field_space's map sends each dof of the fields' own space (one field or several, mixed) to the dof of W that
    holds the same function's value: a function interpolated in both agrees through the map."""
    square = dmesh.create_unit_square(MPI.COMM_WORLD, 3, 2)
    cell = square.ufl_cell()
    vector = ufl.VectorElement("Lagrange", cell, 2)
    all_names = ["velocity", "displacement", "pressure"]
    W = fem.FunctionSpace(square, ufl.MixedElement([vector, vector, ufl.FiniteElement("Lagrange", cell, 1)]))
    V, to_W = field_space(W, all_names, names)
    values = {"velocity": lambda x: np.vstack([x[0] + 2 * x[1], 3 - x[0] * x[1]]),
              "displacement": lambda x: np.vstack([x[1] ** 2, x[0] - x[1]]),
              "pressure": lambda x: 1 + x[0] - 4 * x[1]}
    on_W, on_V = fem.Function(W), fem.Function(V)
    for i, name in enumerate(all_names):
        on_W.sub(i).interpolate(values[name])
    for j, name in enumerate(names):
        on_V.sub(j).interpolate(values[name])
    assert np.abs(on_W.x.array[to_W] - on_V.x.array).max() <= 1e-14
    assert sorted(set(to_W)) == sorted(to_W) and to_W.size == V.dofmap.index_map.size_local
    components = field_components(V, names, ufl.TestFunction)
    assert [len(components[n]) for n in names] == [1 if n == "pressure" else 2 for n in names]



def test_a_block_jacobian_is_posed_on_its_fields_after_a_compilation_changed_the_mesh(tmp_path):
    """direct_jacobian replaces the Jacobian's test function on W by the rows' fields' also when ffcx has compiled a
    form on the mesh in between (which gives the mesh's coordinate element another variant, so a TestFunction(W)
    hashed after it differs from one hashed before): the block form's arguments are on the field spaces, and its
    matrix is the block of the matrix on W."""
    square = dmesh.create_unit_square(MPI.COMM_WORLD, 3, 2)
    cell = square.ufl_cell()
    vector = ufl.VectorElement("Lagrange", cell, 2)
    names = ["velocity", "displacement", "pressure"]
    W = fem.FunctionSpace(square, ufl.MixedElement([vector, vector, ufl.FiniteElement("Lagrange", cell, 1)]))
    pb = SimpleNamespace(W=W, field_names=names, index={n: i for i, n in enumerate(names)})
    w = fem.Function(W)
    w.sub(0).interpolate(lambda x: np.vstack([x[0] ** 2, x[0] * x[1]]))
    w.sub(1).interpolate(lambda x: np.vstack([x[1], 1 + x[0]]))
    w.sub(2).interpolate(lambda x: 2 - x[1])
    v, u, p = ufl.split(w)
    dv, du, dp = ufl.split(ufl.TestFunction(W))
    residual = (ufl.inner(ufl.grad(v) * v, dv) + p * ufl.div(dv) + ufl.inner(ufl.grad(u), ufl.grad(du))
                + ufl.div(v) * dp) * ufl.dx
    hash(residual), [hash(a) for a in residual.arguments()]          # as the engine's forms are, when compiled
    fem.form(ufl.inner(ufl.grad(w), ufl.grad(w)) * ufl.dx, jit_params={"cache_dir": str(tmp_path)})   # compiled
    flow = {"velocity": lambda f: f["velocity"], "pressure": lambda f: f["pressure"]}
    block = direct_jacobian(pb, ["velocity", "pressure"], ["velocity", "pressure"],
                            lambda trial: ufl.derivative(residual, w, direction(pb, flow, trial)))
    V_rows, _ = field_space(W, names, ["velocity", "pressure"])
    size = V_rows.dofmap.index_map.size_global * V_rows.dofmap.index_map_bs
    assert [V.dofmap.index_map.size_global * V.dofmap.index_map_bs for V in block.form.function_spaces] == [size] * 2
    A = fem_petsc.assemble_matrix(block.form)
    A.assemble()
    J = fem_petsc.assemble_matrix(fem.form(ufl.derivative(residual, w, direction(pb, flow))))
    J.assemble()
    rows = PETSc.IS().createGeneral(block.row_to_W.astype(PETSc.IntType))
    cols = PETSc.IS().createGeneral(block.col_to_W.astype(PETSc.IntType))
    on_W = J.createSubMatrix(rows, cols).convert("dense").getDenseArray()
    assert np.abs(A.convert("dense").getDenseArray() - on_W).max() <= 1e-12 * np.abs(on_W).max()

def test_out_of_core_factors_give_the_in_core_solution():
    """SolverOptions.mumps_out_of_core: every MUMPS factor of the partitioned scheme (the wall's and its mass's, the
    mesh's, the urine's) is made out of core (ICNTL(22) = 1, read back from the factors), its files in this
    process's scratch directory while it lives; the same factors, so the same sweeps and the same solution to
    round-off (the memory it saves: benchmarks/coupled_linear_solver.py)."""
    import os

    from ureterfsi.fsi.linear_solvers import out_of_core_directory
    options = dict(coupling_scheme="partitioned", newton_field_rtol=1e-8, **TOL)
    before = set(os.listdir(out_of_core_directory()))
    runs = {core: tube_run(mumps_out_of_core=core, **options) for core in (False, True)}
    factors = {}
    for core, (pb, _) in runs.items():
        blocks = pb.partitioned.factors
        ksps = {"solid": blocks["solid"].ksp, "mass": blocks["solid"].mass_ksp, "flow": blocks["flow"].ksp}
        ksps |= {f"mesh {c}": part.ksp for c, part in enumerate(blocks["mesh"].parts)}
        factors[core] = {n: k.getPC().getFactorMatrix() for n, k in ksps.items()}
    assert {n: f.getMumpsIcntl(22) for n, f in factors[True].items()} == dict.fromkeys(factors[True], 1)
    assert {n: f.getMumpsIcntl(22) for n, f in factors[False].items()} == dict.fromkeys(factors[False], 0)
    assert len(set(os.listdir(out_of_core_directory())) - before) >= len(factors[True])
    (inc, sweeps_inc), (ooc, sweeps_ooc) = runs[False], runs[True]
    assert sweeps_ooc == sweeps_inc
    assert max(field_errors(ooc, inc).values()) <= 1e-12, field_errors(ooc, inc)
    assert "MUMPS out of core" in ooc.options.coupled_solution()


def test_the_set_up_logs_each_blocks_first_lu(caplog):
    """The first LU of each block (the set-up's longest work: minutes on the fine ureter) is logged with its size
    and time, once."""
    import logging
    with caplog.at_level(logging.INFO, logger="ureterfsi.fsi"):
        pb, _ = tube_run(coupling_scheme="partitioned", steps=2, **TOL)
    lines = [r.getMessage() for r in caplog.records if "first Jacobian and LU" in r.getMessage()]
    assert sorted(line.split()[0] for line in lines) == ["flow", "mesh", "solid"], lines
    for line in lines:
        name, size = line.split()[0], int(line.split()[2])
        assert size == pb.partitioned.sizes[name], line
