"""The Mooney-Rivlin wall's first Piola stress in closed form (physics.mooney_rivlin_first_piola) is the derivative
of its strain energy (physics.mooney_rivlin_isochoric_energy) plus the pressure term: compared with UFL's own
derivative of the energy, residual rows and Jacobian, at a large random deformation with all five constants
nonzero, in 3D, plane strain and r-z."""
from __future__ import annotations

import numpy as np
import pytest
import ufl
from dolfinx import fem
from dolfinx import mesh as dmesh
from dolfinx.fem import petsc as fem_petsc
from mpi4py import MPI

from ureterfsi.fsi import physics
from ureterfsi.fsi.materials import MooneyRivlin
from ureterfsi.fsi.operators import Operators

WALL = MooneyRivlin(c10=87.0e3, c01=29.0e3, c20=-4.0e3, c02=11.0e3, c11=7.0e3, bulk_modulus=1.0e7)


def energy_piola(ops, mat, u, pi):
    """P from UFL's derivative of the energy: the definition the closed form must equal."""
    F = ufl.variable(physics.deformation_gradient(ops, u))
    return ufl.diff(physics.mooney_rivlin_isochoric_energy(ops, mat, F), F) + pi * ufl.det(F) * ufl.inv(F).T


def rows_and_jacobian(kind: str, piola):
    """The rows int P : Grad phi + pi r (and their Jacobian) at a fixed random state of u (P2) and pi (P0)."""
    comm = MPI.COMM_WORLD
    if kind == "3d":
        msh = dmesh.create_unit_cube(comm, 3, 3, 3)
    else:
        msh = dmesh.create_rectangle(comm, [np.array([0.5, 0.0]), np.array([1.5, 1.0])], [4, 4])
    ops = Operators(msh, axisymmetric=kind == "rz")
    element = ufl.MixedElement([ufl.VectorElement("Lagrange", msh.ufl_cell(), 2),
                                ufl.FiniteElement("DG", msh.ufl_cell(), 0)])
    W = fem.FunctionSpace(msh, element)
    x = fem.Function(W)
    rng = np.random.default_rng(7)
    V, displacements = W.sub(0).collapse()
    smooth = fem.Function(V)                            # a smooth stretch, shear and bend, |Grad u| up to ~0.4
    stretch = [lambda p: 0.25 * p[0] * p[1] + 0.1 * p[2] ** 2, lambda p: 0.3 * np.sin(p[0]),
               lambda p: 0.2 * p[1] * p[2] - 0.1 * p[0]][:msh.geometry.dim]
    smooth.interpolate(lambda p: np.stack([f(p) for f in stretch]))
    x.x.array[displacements] = smooth.x.array + 0.002 * rng.standard_normal(len(displacements))
    pressures = W.sub(1).collapse()[1]
    x.x.array[pressures] = 2.0e4 * rng.standard_normal(len(pressures))
    u, pi = ufl.split(x)
    phi, r = ufl.TestFunctions(W)
    dx = ufl.dx(metadata={"quadrature_degree": 4})
    R = (ufl.inner(piola(ops, WALL, u, pi), ops.grad(phi)) + pi * r) * ops.weight * dx
    J = fem.assemble_scalar(fem.form(ufl.conditional(ufl.lt(ufl.det(physics.deformation_gradient(ops, u)), 0.7),
                                                     1.0, 0.0) * dx))
    assert J == 0.0                                      # every J >= 0.7: a large but admissible deformation
    b = fem_petsc.assemble_vector(fem.form(R))
    A = fem_petsc.assemble_matrix(fem.form(ufl.derivative(R, x)))
    A.assemble()
    return b.array.copy(), A.convert("dense").getDenseArray()


@pytest.mark.parametrize("kind", ["3d", "plane", "rz"])
def test_closed_form_piola_is_the_energys_derivative(kind):
    b, A = rows_and_jacobian(kind, physics.mooney_rivlin_first_piola)
    b_ref, A_ref = rows_and_jacobian(kind, energy_piola)
    assert np.abs(b_ref).max() > 1e2                     # a deformation that loads the rows
    assert np.abs(b - b_ref).max() <= 1e-12 * np.abs(b_ref).max()
    assert np.abs(A - A_ref).max() <= 1e-11 * np.abs(A_ref).max()
