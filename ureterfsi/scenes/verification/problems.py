"""The small scenes the verification problems are solved on (dolfinx rectangles or tiny gmsh models), with the
study's materials; SI units."""
from __future__ import annotations

import math
from dataclasses import dataclass

import gmsh
import numpy as np
import ufl
from dolfinx import fem
from dolfinx import mesh as dmesh
from dolfinx.fem.petsc import NonlinearProblem
from dolfinx.io import gmshio
from dolfinx.nls.petsc import NewtonSolver
from mpi4py import MPI

from ureterfsi.fsi import (BodyForce, DirichletCondition, FluidRegion, FollowerPressure, LinearElastic, MonolithicFSI,
                           MooneyRivlin, NewtonianFluid, OpenBoundary, Scene, SolidRegion, SurfaceLoad, physics)
from ureterfsi.fsi.operators import Operators
from ureterfsi.fsi.tagging import tag_cells, tag_facets
from ureterfsi.scenes.verification.exact import annular_poiseuille_velocity, annular_poiseuille_flux
from ureterfsi.scenes.verification.norms import integrate, l2_error


# ------------------------------------------------------------------------------------------------
# materials of the verification problems (the study's numbers, config/config.yaml)
# ------------------------------------------------------------------------------------------------
URINE = NewtonianFluid(density=1050.0, dynamic_viscosity=1.3e-3)
URETER_WALL = MooneyRivlin(c10=6.0e4, c01=2.0e4, c20=1.2e5, c02=2.0e4, c11=6.0e4, bulk_modulus=1.0e9,
                           density=1040.0)
STENT = LinearElastic(youngs_modulus=4.22e6, poisson_ratio=0.058, density=1261.1)
REFERENCE_PRESSURE = 130.0


# ------------------------------------------------------------------------------------------------
# scenes
# ------------------------------------------------------------------------------------------------
def channel_scene(axisymmetric=False, wall=URETER_WALL, length=4e-3, fluid_width=4e-3, wall_thickness=1e-3,
                  n_per_mm=2, normal_stress=REFERENCE_PRESSURE, fluid=URINE):
    """Fluid channel 0 < y < fluid_width (plane, y = 0 a symmetry line) or fluid tube 0 < r < fluid_width
    (axisymmetric, x = r, y = z: rotated so the axis is x = 0) under an elastic wall of wall_thickness,
    both fluid ends open at `normal_stress`, wall ends clamped.

    Plane: x along the channel, y across; axisymmetric: x = r across, y = z along. Tags: cells 1 fluid,
    2 wall; facets 1 inlet, 2 outlet, 3 wall ends, 4 symmetry line/axis, 5 outer wall surface."""
    W, H = fluid_width, fluid_width + wall_thickness
    mm = 1e-3
    tol = 1e-9
    if axisymmetric:
        n = (int(round(H / mm * n_per_mm)), int(round(length / mm * n_per_mm)))
        mesh = dmesh.create_rectangle(MPI.COMM_WORLD, [np.zeros(2), np.array([H, length])], n,
                                      diagonal=dmesh.DiagonalType.crossed)
        across, along = 0, 1
    else:
        n = (int(round(length / mm * n_per_mm)), int(round(H / mm * n_per_mm)))
        mesh = dmesh.create_rectangle(MPI.COMM_WORLD, [np.zeros(2), np.array([length, H])], n,
                                      diagonal=dmesh.DiagonalType.crossed)
        across, along = 1, 0
    ct = tag_cells(mesh, {1: lambda x: x[across] < W, 2: lambda x: x[across] > W})
    in_fluid = lambda x: x[across] < W + tol  # noqa: E731
    ft = tag_facets(mesh, {
        1: lambda x: np.isclose(x[along], 0.0, atol=tol) & in_fluid(x),
        2: lambda x: np.isclose(x[along], length, atol=tol) & in_fluid(x),
        3: lambda x: (np.isclose(x[along], 0.0, atol=tol) | np.isclose(x[along], length, atol=tol)) & ~in_fluid(x),
        4: lambda x: np.isclose(x[across], 0.0, atol=tol),
        5: lambda x: np.isclose(x[across], H, atol=tol),
    })
    dirichlet = [
        DirichletCondition("velocity", [3]),
        DirichletCondition("displacement", [1, 2, 3]),
        DirichletCondition("velocity", [4], components=[across]),
        DirichletCondition("displacement", [4], components=[across]),
    ]
    return Scene(mesh=mesh, cell_tags=ct, facet_tags=ft, fluid=FluidRegion([1], fluid),
                 solids=[SolidRegion([2], wall)],
                 open_boundaries=[OpenBoundary([1], normal_stress), OpenBoundary([2], normal_stress)],
                 dirichlet=dirichlet, axisymmetric=axisymmetric, name="channel-at-rest")


@dataclass
class Annulus:
    R1: float = 1.0e-3          # m, inner cylinder (the stent's outer radius)
    R2: float = 4.0e-3          # m, outer cylinder (the ureter's inner radius)
    length: float = 3.0e-3      # m
    p_in: float = 130.05        # Pa (Re = rho v_max (R2 - R1) / mu ~ 35)
    p_out: float = 130.0        # Pa
    fluid: NewtonianFluid = URINE

    @property
    def G(self):
        """-dp/dz = (p_in - p_out) / L."""
        return (self.p_in - self.p_out) / self.length

    def velocity(self, r, log=np.log):
        return annular_poiseuille_velocity(r, self.R1, self.R2, self.G, self.fluid.dynamic_viscosity, log)

    def flux(self):
        return annular_poiseuille_flux(self.R1, self.R2, self.G, self.fluid.dynamic_viscosity)


@dataclass
class Pipe:
    """Steady Poiseuille flow in a pipe of radius R: v = G (R^2 - r^2) / (4 mu), Q = pi G R^4 / (8 mu),
    wall shear stress tau_w = G R / 2 = 4 mu Q / (pi R^3)."""
    radius: float = 1.0e-3      # m (a stent's lumen scale, 10x)
    length: float = 2.0e-3      # m
    p_in: float = 130.02        # Pa
    p_out: float = 130.0        # Pa
    fluid: NewtonianFluid = URINE

    @property
    def G(self):
        return (self.p_in - self.p_out) / self.length

    def flux(self):
        return math.pi * self.G * self.radius**4 / (8.0 * self.fluid.dynamic_viscosity)

    def wall_shear(self):
        return 4.0 * self.fluid.dynamic_viscosity * self.flux() / (math.pi * self.radius**3)


def pipe_axisymmetric_scene(pipe: Pipe, n):
    """r-z rectangle [0, R] x [0, L], n cells across; fluid only: no slip on r = R, v_r = 0 on the axis and on the
    end sections, open ends at p_in (z = 0), p_out (z = L), displacement fixed on every boundary.
    Facets: 1 inlet, 2 outlet, 3 axis r = 0, 4 wall r = R."""
    nz = max(1, int(round(n * pipe.length / pipe.radius)))
    mesh = dmesh.create_rectangle(MPI.COMM_WORLD, [np.zeros(2), np.array([pipe.radius, pipe.length])], (n, nz),
                                  diagonal=dmesh.DiagonalType.crossed)
    tol = 1e-9
    ct = tag_cells(mesh, {1: lambda x: np.full(x.shape[1], True)})
    ft = tag_facets(mesh, {1: lambda x: np.isclose(x[1], 0.0, atol=tol),
                           2: lambda x: np.isclose(x[1], pipe.length, atol=tol),
                           3: lambda x: np.isclose(x[0], 0.0, atol=tol),
                           4: lambda x: np.isclose(x[0], pipe.radius, atol=tol)})
    return Scene(mesh=mesh, cell_tags=ct, facet_tags=ft, fluid=FluidRegion([1], pipe.fluid),
                 open_boundaries=[OpenBoundary([1], pipe.p_in, backflow=0.0),
                                  OpenBoundary([2], pipe.p_out, backflow=0.0)],
                 dirichlet=[DirichletCondition("velocity", [4]),
                            DirichletCondition("velocity", [1, 2, 3], components=[0]),
                            DirichletCondition("displacement", [1, 2, 3, 4])],
                 axisymmetric=True, name="pipe-poiseuille")


def annulus_in_solid_axisymmetric_scene(a: Annulus, n):
    """The axisymmetric annulus (annulus_axisymmetric_scene) inside a held solid ring R2 < r < R2 + (R2 - R1)/2
    (the stent material, displacement fixed on its boundary): the wall r = R2 is an interface between fluid
    (cell tag 1) and solid (2) cells, interior facets tagged 4. Facets: 1 inlet, 2 outlet, 3 r = R1, 4 r = R2,
    5 the solid's boundary."""
    gap = a.R2 - a.R1
    nz = max(1, int(round(n * a.length / gap)))
    outer = a.R2 + 0.5 * gap
    mesh = dmesh.create_rectangle(MPI.COMM_WORLD, [np.array([a.R1, 0.0]), np.array([outer, a.length])],
                                  (n + n // 2, nz), diagonal=dmesh.DiagonalType.crossed)
    tol = 1e-9
    ct = tag_cells(mesh, {1: lambda x: x[0] < a.R2, 2: lambda x: x[0] > a.R2})
    in_fluid = lambda x: x[0] < a.R2 + tol  # noqa: E731
    ft = tag_facets(mesh, {1: lambda x: np.isclose(x[1], 0.0, atol=tol) & in_fluid(x),
                           2: lambda x: np.isclose(x[1], a.length, atol=tol) & in_fluid(x),
                           3: lambda x: np.isclose(x[0], a.R1, atol=tol),
                           5: lambda x: ~in_fluid(x)}, ct, interfaces={4: (1, 2)})
    return Scene(mesh=mesh, cell_tags=ct, facet_tags=ft, fluid=FluidRegion([1], a.fluid),
                 solids=[SolidRegion([2], STENT)],
                 open_boundaries=[OpenBoundary([1], a.p_in, backflow=0.0), OpenBoundary([2], a.p_out, backflow=0.0)],
                 dirichlet=[DirichletCondition("velocity", [3, 5]),
                            DirichletCondition("velocity", [1, 2], components=[0]),
                            DirichletCondition("displacement", [1, 2, 3, 5])],
                 axisymmetric=True, name="annular-poiseuille-in-solid")


def annulus_axisymmetric_scene(a: Annulus, n):
    """r-z rectangle [R1, R2] x [0, L] with n cells across the gap (n * L/(R2 - R1) along); fluid only,
    no slip on r = R1, R2, open ends at p_in (z = 0) and p_out (z = L) without backflow stabilisation
    (the exact solution has inflow at z = 0), displacement fixed on every boundary.

    The engine's open boundary prescribes the full traction sigma n = -f0 n (symmetric stress), while
    Poiseuille flow has a shear traction sigma_rz = mu dv_z/dr on the end sections: the radial velocity
    is therefore also set to zero there (parallel in- and outflow), which replaces the tangential part of
    the condition; the normal part sigma_zz = -p + 2 mu dv_z/dz = -f0 is then exact.
    Facets: 1 inlet, 2 outlet, 3 r = R1, 4 r = R2."""
    gap = a.R2 - a.R1
    nz = max(1, int(round(n * a.length / gap)))
    mesh = dmesh.create_rectangle(MPI.COMM_WORLD, [np.array([a.R1, 0.0]), np.array([a.R2, a.length])], (n, nz),
                                  diagonal=dmesh.DiagonalType.crossed)
    tol = 1e-9
    ct = tag_cells(mesh, {1: lambda x: np.full(x.shape[1], True)})
    ft = tag_facets(mesh, {1: lambda x: np.isclose(x[1], 0.0, atol=tol),
                           2: lambda x: np.isclose(x[1], a.length, atol=tol),
                           3: lambda x: np.isclose(x[0], a.R1, atol=tol),
                           4: lambda x: np.isclose(x[0], a.R2, atol=tol)})
    return Scene(mesh=mesh, cell_tags=ct, facet_tags=ft, fluid=FluidRegion([1], a.fluid),
                 open_boundaries=[OpenBoundary([1], a.p_in, backflow=0.0), OpenBoundary([2], a.p_out, backflow=0.0)],
                 dirichlet=[DirichletCondition("velocity", [3, 4]),
                            DirichletCondition("velocity", [1, 2], components=[0]),
                            DirichletCondition("displacement", [1, 2, 3, 4])],
                 axisymmetric=True, name="annular-poiseuille")


def _quadratic_tetrahedra(h):
    """The current gmsh model meshed at uniform size h with quadratic tetrahedra, as dolfinx (mesh, cell tags,
    facet tags)."""
    gmsh.option.setNumber("Mesh.MeshSizeMin", h)
    gmsh.option.setNumber("Mesh.MeshSizeMax", h)
    gmsh.model.mesh.generate(3)
    gmsh.model.mesh.setOrder(2)
    return gmshio.model_to_mesh(gmsh.model, MPI.COMM_WORLD, 0, gdim=3)


def annulus_3d_scene(a: Annulus, h):
    """Short 3D annulus (gmsh OCC, second-order geometry), z along the axis; same conditions as the
    axisymmetric scene (no slip, transverse velocity zero on the end sections, displacement fixed).
    Facets: 1 inlet, 2 outlet, 3 r = R1, 4 r = R2."""
    gmsh.initialize()
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.model.add("annulus")
        occ = gmsh.model.occ
        outer = occ.addCylinder(0, 0, 0, 0, 0, a.length, a.R2)
        inner = occ.addCylinder(0, 0, 0, 0, 0, a.length, a.R1)
        vol, _ = occ.cut([(3, outer)], [(3, inner)])
        occ.synchronize()
        gmsh.model.addPhysicalGroup(3, [vol[0][1]], 1)
        groups = {1: [], 2: [], 3: [], 4: []}
        for dim, tag in gmsh.model.getBoundary(vol, oriented=False):
            com = occ.getCenterOfMass(dim, tag)
            if abs(com[2]) < 1e-9:
                groups[1].append(tag)
            elif abs(com[2] - a.length) < 1e-9:
                groups[2].append(tag)
            else:
                bb = gmsh.model.getBoundingBox(dim, tag)
                groups[3 if bb[3] < 0.5 * (a.R1 + a.R2) else 4].append(tag)
        for t, surfs in groups.items():
            gmsh.model.addPhysicalGroup(2, surfs, t)
        mesh, ct, ft = _quadratic_tetrahedra(h)
    finally:
        gmsh.finalize()
    return Scene(mesh=mesh, cell_tags=ct, facet_tags=ft, fluid=FluidRegion([1], a.fluid),
                 open_boundaries=[OpenBoundary([1], a.p_in, backflow=0.0), OpenBoundary([2], a.p_out, backflow=0.0)],
                 dirichlet=[DirichletCondition("velocity", [3, 4]),
                            DirichletCondition("velocity", [1, 2], components=[0, 1]),
                            DirichletCondition("displacement", [1, 2, 3, 4])],
                 name="annular-poiseuille-3d")


def _quarter_annulus(name, Ri, Ro):
    """In a new gmsh model `name`: the quarter annulus Ri < r < Ro, x, y >= 0 (built-in kernel); returns its
    surface and {1: inner arc, 2: outer arc, 3: x = 0 line, 4: y = 0 line}."""
    gmsh.option.setNumber("General.Terminal", 0)
    gmsh.model.add(name)
    geo = gmsh.model.geo
    c = geo.addPoint(0, 0, 0)
    p1, p2, p3, p4 = (geo.addPoint(Ri, 0, 0), geo.addPoint(Ro, 0, 0), geo.addPoint(0, Ro, 0), geo.addPoint(0, Ri, 0))
    curves = {4: geo.addLine(p1, p2), 2: geo.addCircleArc(p2, c, p3), 3: geo.addLine(p3, p4),
              1: geo.addCircleArc(p4, c, p1)}
    surf = geo.addPlaneSurface([geo.addCurveLoop([curves[4], curves[2], curves[3], curves[1]])])
    return surf, curves


def quarter_annulus_mesh(Ri, Ro, h, order=2):
    """Quarter annulus Ri < r < Ro, x, y >= 0 (gmsh, curved second-order geometry).
    Facets: 1 inner arc, 2 outer arc, 3 x = 0 line, 4 y = 0 line; cells 1."""
    gmsh.initialize()
    try:
        surf, curves = _quarter_annulus("quarter-annulus", Ri, Ro)
        geo = gmsh.model.geo
        geo.synchronize()
        gmsh.model.addPhysicalGroup(2, [surf], 1)
        for tag, curve in sorted(curves.items()):
            gmsh.model.addPhysicalGroup(1, [curve], tag)
        gmsh.option.setNumber("Mesh.MeshSizeMin", h)
        gmsh.option.setNumber("Mesh.MeshSizeMax", h)
        gmsh.model.mesh.generate(2)
        gmsh.model.mesh.setOrder(order)
        mesh, ct, ft = gmshio.model_to_mesh(gmsh.model, MPI.COMM_WORLD, 0, gdim=2)
    finally:
        gmsh.finalize()
    return mesh, ct, ft


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


def dofs_count(problem):
    return problem.W.dofmap.index_map.size_global * problem.W.dofmap.index_map_bs


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


def annulus_3d_errors(a: Annulus, h, options=None):
    """Steady 3D annular Poiseuille on a gmsh mesh of size h: (tets, dofs, relative L2 error of v_z,
    relative flux error)."""
    scene = annulus_3d_scene(a, h)
    pb = MonolithicFSI(scene, options)
    pb.solve_steady()
    v = pb.field("velocity")
    x = ufl.SpatialCoordinate(pb.mesh)
    r = ufl.sqrt(x[0] ** 2 + x[1] ** 2)
    err, ref = l2_error(v[2], a.velocity(r, log=ufl.ln), mesh=pb.mesh)
    ds = ufl.Measure("ds", domain=pb.mesh, subdomain_data=scene.facet_tags, metadata={"quadrature_degree": 8})
    flux = integrate(v[2], pb.mesh, dx=ds(2)) / a.flux() - 1.0
    return scene.mesh.topology.index_map(3).size_global, dofs_count(pb), err / ref, flux


# ------------------------------------------------------------------------------------------------
# solids under body forces and follower pressures
# ------------------------------------------------------------------------------------------------
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


def mean_facet_value(problem, expr, tag):
    """(int_tag expr dS) / (int_tag dS) over reference facets (no axisymmetric weight)."""
    mesh = problem.mesh
    ds = ufl.Measure("ds", domain=mesh, subdomain_data=problem.scene.facet_tags, metadata={"quadrature_degree": 8})
    return integrate(expr, mesh, dx=ds(tag)) / integrate(fem.Constant(mesh, 1.0), mesh, dx=ds(tag))


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
        surf, curves = _quarter_annulus("quarter-tube", tube.Ri, tube.Ro)
        geo = gmsh.model.geo
        out = geo.extrude([(2, surf)], 0, 0, h, numElements=[1])
        geo.synchronize()
        # extrude returns [top, volume, then one lateral surface per bounding curve in curve-loop order]
        top, vol, lateral = out[0][1], out[1][1], [e[1] for e in out[2:]]
        gmsh.model.addPhysicalGroup(3, [vol], 1)
        for tag, side in zip((4, 2, 3, 1), lateral):
            gmsh.model.addPhysicalGroup(2, [side], tag)
        gmsh.model.addPhysicalGroup(2, [surf, top], 5)
        mesh, ct, ft = _quadratic_tetrahedra(h)
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
