"""Verification scenes of flow: the channel beside a wall, Poiseuille flow in a rigid pipe and in an annulus
(r-z, inside a solid, 3D) and the 3D annulus's errors against the exact solution."""
from __future__ import annotations

import math
from dataclasses import dataclass

import gmsh
import numpy as np
import ufl
from dolfinx import mesh as dmesh
from mpi4py import MPI

from ureterfsi.fsi import (DirichletCondition, FluidRegion, MonolithicFSI, NewtonianFluid, OpenBoundary, Scene,
                           SolidRegion)
from ureterfsi.fsi.tagging import tag_cells, tag_facets
from ureterfsi.scenes.verification.exact import annular_poiseuille_flux, annular_poiseuille_velocity
from ureterfsi.scenes.verification.materials import REFERENCE_PRESSURE, STENT, URETER_WALL, URINE
from ureterfsi.scenes.verification.meshing import quadratic_tetrahedra
from ureterfsi.scenes.verification.norms import dofs_count, integrate, l2_error


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
        mesh, ct, ft = quadratic_tetrahedra(h)
    finally:
        gmsh.finalize()
    return Scene(mesh=mesh, cell_tags=ct, facet_tags=ft, fluid=FluidRegion([1], a.fluid),
                 open_boundaries=[OpenBoundary([1], a.p_in, backflow=0.0), OpenBoundary([2], a.p_out, backflow=0.0)],
                 dirichlet=[DirichletCondition("velocity", [3, 4]),
                            DirichletCondition("velocity", [1, 2], components=[0, 1]),
                            DirichletCondition("displacement", [1, 2, 3, 4])],
                 name="annular-poiseuille-3d")


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
