"""Verification scenes of solids under their weight: the hanging bar (3D or r-z) and the confined column (plane
strain)."""
from __future__ import annotations

import numpy as np
import ufl
from dolfinx import mesh as dmesh
from mpi4py import MPI

from ureterfsi.fsi import BodyForce, DirichletCondition, LinearElastic, Scene, SolidRegion
from ureterfsi.fsi.tagging import tag_cells, tag_facets


def hanging_bar_scene(mat: LinearElastic, weight, axisymmetric=False, radius=2e-3, length=10e-3, n=(2, 4)):
    """Bar of square cross-section radius x radius (3D, create_box: n[0] x n[0] x n[1] cells) or round cylinder
    of `radius` (axisymmetric r-z, n[0] x n[1] cells) and `length`, clamped at z = 0, body force `weight` (N/m^3)
    along +z. Facets: 1 the support z = 0, 2 the axis r = 0 (axisymmetric); cells 1."""
    tol = 1e-12
    if axisymmetric:
        mesh = dmesh.create_rectangle(MPI.COMM_WORLD, [np.zeros(2), np.array([radius, length])], n,
                                      diagonal=dmesh.DiagonalType.crossed)
    else:
        mesh = dmesh.create_box(MPI.COMM_WORLD, [np.zeros(3), np.array([radius, radius, length])], (n[0], n[0], n[1]))
    z = mesh.geometry.dim - 1
    ct = tag_cells(mesh, {1: lambda x: np.full(x.shape[1], True)})
    ft = tag_facets(mesh, {1: lambda x: np.isclose(x[z], 0.0, atol=tol), 2: lambda x: np.isclose(x[0], 0.0, atol=tol)})
    dirichlet = [DirichletCondition("displacement", [1]), DirichletCondition("velocity", [1])]
    if axisymmetric:
        dirichlet += [DirichletCondition("displacement", [2], components=[0]),
                      DirichletCondition("velocity", [2], components=[0])]
    return Scene(mesh=mesh, cell_tags=ct, facet_tags=ft, solids=[SolidRegion([1], mat)],
                 body_forces=[BodyForce([1], lambda X, t: ufl.as_vector([0.0, 0.0, weight]))],
                 dirichlet=dirichlet, axisymmetric=axisymmetric, name="hanging-bar")


def confined_column_scene(mat, weight, n, width=2e-3, length=10e-3):
    """Plane-strain column [0, width] x [0, length] (1 x n crossed cells), u_x = v_x = 0 on x = 0 and x = width
    (frictionless channel walls), u = v = 0 on y = 0, body force `weight` (N/m^3) along +y.
    Facets: 1 the support y = 0, 2 the channel walls, 3 the free top y = length; cells 1."""
    tol = 1e-12
    mesh = dmesh.create_rectangle(MPI.COMM_WORLD, [np.zeros(2), np.array([width, length])], (1, n),
                                  diagonal=dmesh.DiagonalType.crossed)
    ct = tag_cells(mesh, {1: lambda x: np.full(x.shape[1], True)})
    ft = tag_facets(mesh, {1: lambda x: np.isclose(x[1], 0.0, atol=tol),
                           2: lambda x: np.isclose(x[0], 0.0, atol=tol) | np.isclose(x[0], width, atol=tol),
                           3: lambda x: np.isclose(x[1], length, atol=tol)})
    return Scene(mesh=mesh, cell_tags=ct, facet_tags=ft, solids=[SolidRegion([1], mat)],
                 body_forces=[BodyForce([1], lambda X, t: ufl.as_vector([0.0, weight]))],
                 dirichlet=[DirichletCondition("displacement", [1]), DirichletCondition("velocity", [1]),
                            DirichletCondition("displacement", [2], components=[0]),
                            DirichletCondition("velocity", [2], components=[0])],
                 name="confined-column")
