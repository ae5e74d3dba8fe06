"""The fluid alone in an expanding axisymmetric tube (tests/fsi/test_fluid_alone.py's case, also solved by
tests/fsi/test_linearly_implicit.py and tests/fsi/test_coupled_linear_solver.py): radius R0, closed at z = 0 (no slip),
open at z = L, its wall expanding uniformly, R(t) = R0 (1 + A sin(OMEGA t))."""
import math

import numpy as np
import ufl
from dolfinx import fem
from dolfinx import mesh as dmesh
from mpi4py import MPI

from ureterfsi.fsi import (DirichletCondition, FluidRegion, MonolithicFSI, NewtonianFluid, OpenBoundary, Scene,
                           SolverOptions)
from ureterfsi.fsi import physics
from ureterfsi.fsi.tagging import tag_cells, tag_facets

R0, L, A, OMEGA = 1e-3, 4e-3, 0.05, 2 * math.pi * 5.0    # m, m, -, rad/s
FLUID, BOTTOM, TOP, WALL, AXIS = 1, 1, 2, 3, 4


def wall_displacement(x, t):
    """u_r = a sin(omega t) r (uniform radial stretch of the whole fluid), u_z = 0."""
    return np.vstack([A * math.sin(OMEGA * t) * x[0], np.zeros_like(x[1])])


def tube(n=8):
    msh = dmesh.create_rectangle(MPI.COMM_WORLD, [np.array([0.0, 0.0]), np.array([R0, L])], [n, 4 * n],
                                 dmesh.CellType.triangle)
    ct = tag_cells(msh, {FLUID: lambda x: np.full(x.shape[1], True)})
    eps = 1e-12
    ft = tag_facets(msh, {BOTTOM: lambda x: x[1] < eps, TOP: lambda x: x[1] > L - eps,
                          WALL: lambda x: x[0] > R0 - eps, AXIS: lambda x: x[0] < eps})
    return msh, ct, ft


KEEP = object()


def run(dt, steps, coupling="monolithic", mesh_motion=None, swap_to=KEEP, **options):
    """The tube's flow over `steps` steps: (outflow per step, fluid volume, problem); `swap_to`: a mesh motion
    given to the posed problem (MonolithicFSI.use_mesh_motion) before its run."""
    msh, ct, ft = tube()
    scene = Scene(msh, ct, ft, fluid=FluidRegion([FLUID], NewtonianFluid(1000.0, 1e-3)), mesh_motion=mesh_motion,
                  open_boundaries=[OpenBoundary([TOP], normal_stress=0.0, backflow=1.0)],
                  dirichlet=[DirichletCondition("velocity", [BOTTOM]),
                             DirichletCondition("velocity", [WALL],
                                                lambda x, t: np.vstack([A * OMEGA * math.cos(OMEGA * t) * x[0],
                                                                        np.zeros_like(x[1])])),
                             DirichletCondition("velocity", [AXIS], components=[0]),
                             DirichletCondition("displacement", [WALL, BOTTOM, TOP], wall_displacement),
                             DirichletCondition("displacement", [AXIS], components=[0])],
                  axisymmetric=True)
    pb = MonolithicFSI(scene, SolverOptions(mesh_motion_coupling=coupling, **options))
    if swap_to is not KEEP:
        pb.use_mesh_motion(swap_to)
    pb.solve_steady()
    parts, dots = pb.split(), pb.split(pb.x_dot)
    F = physics.deformation_gradient(pb.ops, parts["displacement"])
    J = ufl.det(F)
    n_da = J * ufl.inv(F).T * pb.ops.normal()
    rel = pb.ops.vec(parts["velocity"]) - pb.ops.vec(dots["displacement"])
    outflow = fem.form(ufl.dot(rel, n_da) * pb.ops.weight * pb.ds(TOP))
    volume = fem.form(J * pb.ops.weight * pb.dx(FLUID))
    q, vol = [], [fem.assemble_scalar(volume)]
    for _ in range(steps):
        pb.step(dt)
        q.append(fem.assemble_scalar(outflow))
        vol.append(fem.assemble_scalar(volume))
    return np.array(q), np.array(vol), pb
