"""Verification scenes of the inflated Mooney-Rivlin tube (plane strain): the quarter tube under a dead load or a
follower pressure (2D, r-z, 3D), its mean deformed inner radius, and the locking pure-displacement contrast."""
from __future__ import annotations

from dataclasses import dataclass

import gmsh
import numpy as np
import ufl
from dolfinx import fem
from dolfinx import mesh as dmesh
from dolfinx.fem.petsc import NonlinearProblem
from dolfinx.nls.petsc import NewtonSolver
from mpi4py import MPI

from ureterfsi.fsi import (DirichletCondition, FollowerPressure, MooneyRivlin, Scene, SolidRegion, SurfaceLoad,
                           physics)
from ureterfsi.fsi.operators import Operators
from ureterfsi.fsi.tagging import tag_cells, tag_facets
from ureterfsi.scenes.verification.materials import URETER_WALL
from ureterfsi.scenes.verification.meshing import quadratic_tetrahedra, quarter_annulus_mesh, quarter_annulus_model
from ureterfsi.scenes.verification.norms import integrate


@dataclass
class Tube:
    Ri: float = 4.0e-3
    Ro: float = 5.0e-3
    material: MooneyRivlin = URETER_WALL


def radial_dead_load(p0, ramp=None):
    """Traction per reference area P N = -p0 g(t) N on the inner surface (N the outward normal of the
    solid there, -e_R: the load pushes outward); `ramp(t)` a UFL-friendly time profile (default 1)."""
    def traction(X, t, N):
        amp = p0 if ramp is None else p0 * ramp(t)
        return -amp * N
    return traction


def tube_scene(tube: Tube, h, p0, ramp=None, order=2, follower=False):
    """Plane-strain quarter tube, solid alone, radial dead load p0 on the inner arc (follower=True: the
    follower pressure p0 ramp(t), P N = -p J F^-T N), symmetry on x = 0 (u_x = v_x = 0) and y = 0
    (u_y = v_y = 0), outer surface free."""
    mesh, ct, ft = quarter_annulus_mesh(tube.Ri, tube.Ro, h, order)
    if follower:
        loads = dict(pressure_loads=[FollowerPressure([1], lambda X, t: p0 if ramp is None else p0 * ramp(t))])
    else:
        loads = dict(loads=[SurfaceLoad([1], radial_dead_load(p0, ramp))])
    return Scene(mesh=mesh, cell_tags=ct, facet_tags=ft, solids=[SolidRegion([1], tube.material)], **loads,
                 dirichlet=[DirichletCondition("displacement", [3], components=[0]),
                            DirichletCondition("velocity", [3], components=[0]),
                            DirichletCondition("displacement", [4], components=[1]),
                            DirichletCondition("velocity", [4], components=[1])],
                 name="mooney-rivlin-tube")


def tube_inner_radius(problem, tube: Tube):
    """Mean deformed inner radius: (int_inner |X + u| dS) / (int_inner dS) on the reference inner arc."""
    mesh = problem.mesh
    u = problem.field("displacement")
    X = ufl.SpatialCoordinate(mesh)
    ds = ufl.Measure("ds", domain=mesh, subdomain_data=problem.scene.facet_tags, metadata={"quadrature_degree": 8})
    x = X + u
    num = integrate(ufl.sqrt(ufl.dot(x, x)), mesh, dx=ds(1))
    den = integrate(fem.Constant(mesh, 1.0), mesh, dx=ds(1))
    return num / den


def pure_displacement_tube_inner_radius(tube: Tube, h, p0, degree=1, order=2, load_steps=4):
    """Contrast to the engine's mixed u-pi formulation: the same plane-strain tube and dead load solved in
    pure displacement form, W = W_iso + kappa/2 (J - 1)^2 with Lagrange-`degree` displacement (dolfinx
    Newton). With kappa/(C10 + C01) ~ 1e4 this locks: the returned inner radius is far too small."""
    mesh, ct, ft = quarter_annulus_mesh(tube.Ri, tube.Ro, h, order)
    ops = Operators(mesh)
    V = fem.VectorFunctionSpace(mesh, ("Lagrange", degree))
    u, phi = fem.Function(V), ufl.TestFunction(V)
    F = ufl.variable(physics.deformation_gradient(ops, u))
    J = ufl.det(F)
    mat = tube.material
    W = physics.mooney_rivlin_isochoric_energy(ops, mat, F) + 0.5 * mat.bulk_modulus * (J - 1.0) ** 2
    P = ufl.diff(W, F)
    md = {"quadrature_degree": 4}
    ds = ufl.Measure("ds", domain=mesh, subdomain_data=ft, metadata=md)
    N = ufl.FacetNormal(mesh)
    load = fem.Constant(mesh, 0.0)
    R = ufl.inner(P, ufl.grad(phi)) * ufl.dx(metadata=md) + load * ufl.dot(N, phi) * ds(1)
    fdim = mesh.topology.dim - 1
    bcs = []
    for tag, comp in ((3, 0), (4, 1)):
        sub = V.sub(comp)
        collapsed, _ = sub.collapse()
        dofs = fem.locate_dofs_topological((sub, collapsed), fdim, ft.find(tag))
        bcs.append(fem.dirichletbc(fem.Function(collapsed), dofs, sub))
    solver = NewtonSolver(mesh.comm, NonlinearProblem(R, u, bcs))
    solver.convergence_criterion = "incremental"
    solver.rtol, solver.atol, solver.max_it = 1e-10, 1e-14, 50
    for s in range(1, load_steps + 1):
        load.value = p0 * s / load_steps
        solver.solve(u)
    X = ufl.SpatialCoordinate(mesh)
    x = X + u
    num = integrate(ufl.sqrt(ufl.dot(x, x)), mesh, dx=ds(1))
    den = integrate(fem.Constant(mesh, 1.0), mesh, dx=ds(1))
    return num / den


def tube_axisymmetric_scene(tube: Tube, n, pressure, follower=True, height=None):
    """Plane-strain (lambda_z = 1) inflation in the r-z mode: the rectangle [Ri, Ro] x [0, height] (n x 1 crossed
    cells, height = (Ro - Ri)/n), u_z = v_z = 0 on z = 0 and z = height, outer surface free, and on the inner
    surface either a follower pressure p(t) (FollowerPressure, P N = -p J F^-T N) or the dead load of the same
    magnitude (SurfaceLoad, P N = -p N). `pressure(t)` returns UFL. Facets: 1 inner, 2 outer, 3 ends."""
    height = height or (tube.Ro - tube.Ri) / n
    tol = 1e-12
    mesh = dmesh.create_rectangle(MPI.COMM_WORLD, [np.array([tube.Ri, 0.0]), np.array([tube.Ro, height])], (n, 1),
                                  diagonal=dmesh.DiagonalType.crossed)
    ct = tag_cells(mesh, {1: lambda x: np.full(x.shape[1], True)})
    ft = tag_facets(mesh, {1: lambda x: np.isclose(x[0], tube.Ri, atol=tol),
                           2: lambda x: np.isclose(x[0], tube.Ro, atol=tol),
                           3: lambda x: np.isclose(x[1], 0.0, atol=tol) | np.isclose(x[1], height, atol=tol)})
    if follower:
        loads = dict(pressure_loads=[FollowerPressure([1], lambda X, t: pressure(t))])
    else:
        loads = dict(loads=[SurfaceLoad([1], lambda X, t, N: -pressure(t) * N)])
    return Scene(mesh=mesh, cell_tags=ct, facet_tags=ft, solids=[SolidRegion([1], tube.material)],
                 dirichlet=[DirichletCondition("displacement", [3], components=[1]),
                            DirichletCondition("velocity", [3], components=[1])],
                 axisymmetric=True, name="mooney-rivlin-tube-rz", **loads)


def quarter_tube_3d_scene(tube: Tube, h, pressure, follower=True):
    """Plane-strain (lambda_z = 1) inflation in 3D: the quarter annulus Ri < r < Ro, x, y >= 0 (gmsh,
    second-order geometry, size h) extruded by h into one layer of tetrahedra; u_x = v_x = 0 on x = 0,
    u_y = v_y = 0 on y = 0, u_z = v_z = 0 on both end faces, outer surface free, and on the inner surface a
    follower pressure p(t) (or the dead load P N = -p N). Facets: 1 inner, 2 outer, 3 x = 0, 4 y = 0, 5 ends."""
    gmsh.initialize()
    try:
        surf, curves = quarter_annulus_model("quarter-tube", tube.Ri, tube.Ro)
        geo = gmsh.model.geo
        out = geo.extrude([(2, surf)], 0, 0, h, numElements=[1])
        geo.synchronize()
        # extrude returns [top, volume, then one lateral surface per bounding curve in curve-loop order]
        top, vol, lateral = out[0][1], out[1][1], [e[1] for e in out[2:]]
        gmsh.model.addPhysicalGroup(3, [vol], 1)
        for tag, side in zip((4, 2, 3, 1), lateral):
            gmsh.model.addPhysicalGroup(2, [side], tag)
        gmsh.model.addPhysicalGroup(2, [surf, top], 5)
        mesh, ct, ft = quadratic_tetrahedra(h)
    finally:
        gmsh.finalize()
    if follower:
        loads = dict(pressure_loads=[FollowerPressure([1], lambda X, t: pressure(t))])
    else:
        loads = dict(loads=[SurfaceLoad([1], lambda X, t, N: -pressure(t) * N)])
    dirichlet = [DirichletCondition(f, [tag], components=[comp])
                 for tag, comp in ((3, 0), (4, 1), (5, 2)) for f in ("displacement", "velocity")]
    return Scene(mesh=mesh, cell_tags=ct, facet_tags=ft, solids=[SolidRegion([1], tube.material)],
                 dirichlet=dirichlet, name="mooney-rivlin-tube-3d", **loads)
