"""The ALE mesh motion's Jacobian-based stiffening (SolverOptions.mesh_jacobian_stiffening,
physics.mesh_motion_residual): k J^-chi with J = det(I + Grad u).

On the unit square with the whole boundary displaced: an affine boundary motion is extended exactly whatever
chi (J is constant, so the stiffness is too); a bump pushed 45 % into the square from its top edge keeps its
cells open only when stiffened, and Newton on the derived Jacobian converges quadratically. In the engine: the
option is refused where the mesh block is kept as a fixed operator, and the tube's steps are unchanged but for
the fluid mesh's interior."""
from __future__ import annotations

import numpy as np
import pytest
import ufl
from dolfinx import fem
from dolfinx import mesh as dmesh
from dolfinx.fem import petsc as fem_petsc
from mpi4py import MPI
from petsc4py import PETSc

from helpers.engine_cases import field_errors, tube_problem, tube_run
from ureterfsi.fsi import SolverOptions, physics
from ureterfsi.fsi.operators import Operators

AFFINE = np.array([[0.3, 0.5], [-0.2, -0.4]])          # det(I + A) = 0.88


def extend(boundary, kind: str, chi: float, n: int = 12, increments: int = 4):
    """The extension of `boundary`(x) into the unit square (P2, n x n), its motion applied in `increments` equal
    parts, each solved by Newton on the derived Jacobian: (u, residual norms of the last increment, min_cells J)."""
    msh = dmesh.create_unit_square(MPI.COMM_WORLD, n, n)
    V = fem.VectorFunctionSpace(msh, ("Lagrange", 2))
    u, du, g = fem.Function(V), fem.Function(V), fem.Function(V)
    dx = ufl.dx(metadata={"quadrature_degree": 4})    # one rule for the residual and its Jacobian, as the engine
    R = physics.mesh_motion_residual(Operators(msh), kind, u, ufl.TestFunction(V), fem.Constant(msh, 1.0), dx, chi)
    residual, jacobian = fem.form(R), fem.form(ufl.derivative(R, u))
    facets = dmesh.locate_entities_boundary(msh, 1, lambda x: np.full(x.shape[1], True))
    bc = fem.dirichletbc(g, fem.locate_dofs_topological(V, 1, facets))
    ksp = PETSc.KSP().create(msh.comm)
    ksp.setType("preonly")
    ksp.getPC().setType("lu")
    for k in range(1, increments + 1):
        g.interpolate(lambda x: k / increments * boundary(x))
        norms = []
        for _ in range(20):
            b = fem_petsc.assemble_vector(residual)
            fem_petsc.apply_lifting(b, [jacobian], [[bc]], x0=[u.vector], scale=-1.0)
            b.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
            fem_petsc.set_bc(b, [bc], u.vector, -1.0)
            norms.append(b.norm())
            if norms[-1] < 1e-11:
                break
            A = fem_petsc.assemble_matrix(jacobian, bcs=[bc])
            A.assemble()
            ksp.setOperators(A)
            ksp.solve(b, du.vector)
            u.vector.axpy(-1.0, du.vector)
            u.x.scatter_forward()
    Q = fem.FunctionSpace(msh, ("DG", 0))
    J = fem.Function(Q)
    J.interpolate(fem.Expression(ufl.det(ufl.Identity(2) + ufl.grad(u)), Q.element.interpolation_points()))
    return u, norms, msh.comm.allreduce(J.x.array.min(), MPI.MIN)


def affine(x):
    return AFFINE @ x[:2]


def bump(x):
    """The top edge pushed down by 0.45 sin^2(pi x): the cells under its middle are squeezed."""
    return np.vstack([0.0 * x[0], -0.45 * np.sin(np.pi * x[0]) ** 2 * np.isclose(x[1], 1.0)])


@pytest.mark.parametrize("kind", ["harmonic", "elastic"])
def test_affine_motion_is_extended_exactly_whatever_the_stiffening(kind):
    for chi in (0.0, 2.0):
        u, norms, jmin = extend(affine, kind, chi, increments=1)
        exact = fem.Function(u.function_space)
        exact.interpolate(affine)
        assert np.abs(u.x.array - exact.x.array).max() < 1e-12, (kind, chi)
        assert jmin == pytest.approx(np.linalg.det(np.eye(2) + AFFINE), abs=1e-12)


@pytest.mark.parametrize("kind, plain_below, stiffened_above", [("harmonic", 0.0, 0.15), ("elastic", 0.1, 0.33)])
def test_jacobian_stiffening_keeps_squeezed_cells_open(kind, plain_below, stiffened_above):
    """The bump inverts (harmonic, min J -0.56) or nearly (elastic, 0.08) the plain extension's cells; with
    chi = 1 the smallest J is 0.16 (harmonic) and 0.34 (elastic). Newton's observed order >= 1.8 in the last
    increment (the derived Jacobian is exact)."""
    _, _, plain = extend(bump, kind, 0.0)
    _, norms, stiffened = extend(bump, kind, 1.0)
    assert plain < plain_below and stiffened > stiffened_above, (plain, stiffened)
    r = [v for v in norms if v > 1e-10][-3:]
    assert len(r) == 3 and np.log(r[2] / r[1]) / np.log(r[1] / r[0]) >= 1.8, norms


@pytest.mark.parametrize("options", [dict(coupling_scheme="partitioned"), dict(linear_solver="block_gauss_seidel")])
def test_stiffening_is_refused_where_the_mesh_block_is_kept_fixed(options):
    with pytest.raises(ValueError, match="mesh_jacobian_stiffening > 0 .* needs mesh_motion_coupling 'monolithic'"):
        tube_problem(options=SolverOptions(mesh_jacobian_stiffening=1.0, **options))
    with pytest.raises(ValueError, match="mesh_jacobian_stiffening >= 0, got -1.0"):
        tube_problem(options=SolverOptions(mesh_jacobian_stiffening=-1.0))


def test_stiffened_tube_steps_move_only_the_fluid_mesh():
    """The tube's wall barely strains the urine's cells (J >= 0.9997): the stiffened steps take Newton's iterations
    of the plain ones; the wall's pressure agrees to 1e-8, the urine's velocity and pressure (at nodes the ALE map
    now puts elsewhere) to 1e-4, and the fluid mesh moves differently (displacement 5.7e-4 of its largest)."""
    plain, iterations = tube_run(steps=3)
    stiffened, stiffened_iterations = tube_run(steps=3, mesh_jacobian_stiffening=2.0)
    assert stiffened_iterations == iterations
    errors = field_errors(stiffened, plain)
    assert errors["solid_pressure"] < 1e-8 and max(errors["velocity"], errors["pressure"]) < 1e-4, errors
    assert 1e-5 < errors["displacement"] < 1e-3, errors
