"""A rigid axisymmetric pipe with open ends: the verification scene of the lumped end conditions
(fsi.end_conditions; tests/fsi/test_end_conditions.py, benchmarks/end_conditions.py).

Quasi-steady Poiseuille flow through it has the resistance R = dp/Q = 8 mu L / (pi a^4); a compliance C upstream
then relaxes as p(t) = p_out + (p(0) - p_out) exp(-t / (R C)).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from dolfinx import mesh as dmesh
from mpi4py import MPI

from ureterfsi.mesh import tags

from ..fsi import DirichletCondition, FluidRegion, NewtonianFluid, OpenBoundary, Scene
from ..fsi.tagging import tag_cells, tag_facets

# the ureter's facet tags: the study's probes (flux_volume_forms, study.end_probes) apply as they are
INLET, OUTLET, AXIS, WALL = tags.INLET, tags.OUTLET, tags.AXIS, tags.FLUID_URETER


@dataclass
class RigidPipe:
    radius: float = 1.0e-3                 # m
    length: float = 4.0e-3                 # m
    # a viscous, light fluid: its inertance over its resistance, rho a^2 / (6 mu) = 0.17 us (low-frequency Womersley
    # flow), is negligible against the relaxation times posed on it, so the flow is quasi-steady Poiseuille flow
    # (with urine's density that lag shifts a 0.1 s relaxation by 0.17 %)
    fluid: NewtonianFluid = NewtonianFluid(density=1.0, dynamic_viscosity=1.0)

    @property
    def resistance(self) -> float:
        """Poiseuille resistance 8 mu L / (pi a^4) (Pa s/m^3)."""
        return 8.0 * self.fluid.dynamic_viscosity * self.length / (math.pi * self.radius**4)


def rigid_pipe_scene(pipe: RigidPipe, n: int, inlet: OpenBoundary, outlet: OpenBoundary) -> Scene:
    """r-z rectangle [0, a] x [0, L], n cells across the radius (crossed diagonals); no slip on r = a, no radial
    velocity on the axis and on the end faces (parallel in- and outflow: the normal stress condition is then exact
    for Poiseuille flow), mesh fixed. `inlet`, `outlet`: open boundaries on the tags INLET (z = 0), OUTLET (z = L)."""
    nz = max(1, int(round(n * pipe.length / pipe.radius)))
    mesh = dmesh.create_rectangle(MPI.COMM_WORLD, [np.array([0.0, 0.0]), np.array([pipe.radius, pipe.length])],
                                  (n, nz), diagonal=dmesh.DiagonalType.crossed)
    tol = 1e-9 * pipe.length
    ct = tag_cells(mesh, {1: lambda x: np.full(x.shape[1], True)})
    ft = tag_facets(mesh, {INLET: lambda x: np.isclose(x[1], 0.0, atol=tol),
                           OUTLET: lambda x: np.isclose(x[1], pipe.length, atol=tol),
                           AXIS: lambda x: np.isclose(x[0], 0.0, atol=tol),
                           WALL: lambda x: np.isclose(x[0], pipe.radius, atol=tol)})
    return Scene(mesh=mesh, cell_tags=ct, facet_tags=ft, fluid=FluidRegion([1], pipe.fluid),
                 open_boundaries=[inlet, outlet],
                 dirichlet=[DirichletCondition("velocity", [WALL]),
                            DirichletCondition("velocity", [INLET, OUTLET, AXIS], components=[0]),
                            DirichletCondition("displacement", [INLET, OUTLET, AXIS, WALL])],
                 axisymmetric=True, name="rigid-pipe")
