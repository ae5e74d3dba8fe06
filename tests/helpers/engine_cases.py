"""Shared test scenes for the FSI engine: a miniature of the stented-ureter problem.

Axisymmetric (r, z) fluid-filled elastic tube: fluid 0 < r < R_i, Mooney-Rivlin wall R_i < r < R_o,
length L. The wall ends are clamped (u = v = 0), the fluid ends are open at a reference normal stress
(with the ALE mesh fixed there), the axis is a symmetry line (u_r = v_r = 0), and a travelling
Gaussian outward traction acts on the outer wall:

    t(Z, t) = amp * ramp(t) * exp(-((Z - z0 - c t) / width)^2) N,   ramp(t) = 1 - exp(-t / t_ramp).

amp and c are fem.Constants (case.amplitude, case.speed), so tests can change the load without a new
form compilation. Materials and geometry are fixed so every test shares the same JIT-compiled forms.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import ufl
from dolfinx import fem, graph
from dolfinx import mesh as dmesh
from mpi4py import MPI

from ureterfsi.fsi import (DirichletCondition, FluidRegion, MonolithicFSI, MooneyRivlin, NewtonianFluid,
                           Observer, OpenBoundary, Scene, SolidRegion, SolverOptions, SurfaceLoad)
from ureterfsi.fsi.tagging import tag_cells, tag_facets

# geometry (m)
R_I, R_O, LENGTH = 1.5e-3, 2.5e-3, 20e-3
# tags
FLUID, WALL = 1, 2
INLET, OUTLET, WALL_ENDS, OUTER, AXIS = 1, 2, 3, 4, 5
# load
AMPLITUDE = 3.0e3       # Pa (about 5 % hoop strain)
SPEED = 40e-3           # m/s
WIDTH = 2.5e-3          # m
Z0 = 6e-3               # m, load centre at t = 0
T_RAMP = 0.02           # s
REFERENCE_STRESS = 0.0  # Pa, normal stress at the open ends

FLUID_MATERIAL = NewtonianFluid(density=1000.0, dynamic_viscosity=3.5e-3)
WALL_MATERIAL = MooneyRivlin(c10=30e3, c01=5e3, bulk_modulus=5e6, density=1100.0)


@dataclass
class TubeCase:
    scene: Scene
    amplitude: fem.Constant
    speed: fem.Constant

    @property
    def mesh(self):
        return self.scene.mesh


def tube_mesh(comm=MPI.COMM_WORLD, n_fluid=4, n_wall=2, n_axial=40, partition=None):
    """Structured triangle mesh of [0, R_o] x [0, L] with a mesh line at r = R_i.

    partition=None: the default partitioner (shared-facet ghosts). partition="interface": an
    adversarial split along the fluid-solid interface (fluid cells on rank 0, wall cells on the last
    rank) with shared-facet ghosts; "interface-noghost": the same without ghost cells, so every
    interface dof sees its fluid cells on one process and its solid cells on another."""
    nr = n_fluid + n_wall
    corners = [np.array([0.0, 0.0]), np.array([1.0, 1.0])]
    if partition is None:
        mesh = dmesh.create_rectangle(comm, corners, [nr, n_axial], dmesh.CellType.triangle,
                                      diagonal=dmesh.DiagonalType.right)
    elif partition in ("interface", "interface-noghost"):
        def partitioner(comm_, nparts, tdim, cells, ghost_mode):
            # dolfinx 0.5 always asks for facet ghosts (it finds the shared vertices through them):
            # links of cell c = [owner, owners of the cells across its facets (if different)].
            # create_rectangle numbers vertex (ix, iy) as iy (nr + 1) + ix.
            a = cells.array.reshape(-1, 3)
            owner = np.where((a % (nr + 1)).mean(axis=1) < n_fluid, 0, nparts - 1).astype(np.int32)
            facets = {}
            for c, verts in enumerate(a):
                for i in range(3):
                    facets.setdefault(tuple(sorted(np.delete(verts, i))), []).append(c)
            links = [[o] for o in owner]
            for pair in facets.values():
                if len(pair) == 2 and owner[pair[0]] != owner[pair[1]]:
                    links[pair[0]].append(owner[pair[1]])
                    links[pair[1]].append(owner[pair[0]])
            links = [sorted(set(l), key=lambda r, o=l[0]: r != o) for l in links]
            offsets = np.cumsum([0] + [len(l) for l in links]).astype(np.int32)
            data = np.array([r for l in links for r in l], dtype=np.int32)
            return graph.create_adjacencylist(data, offsets)
        ghosts = dmesh.GhostMode.none if partition == "interface-noghost" else dmesh.GhostMode.shared_facet
        mesh = dmesh.create_rectangle(comm, corners, [nr, n_axial], dmesh.CellType.triangle,
                                      ghosts, partitioner, dmesh.DiagonalType.right)
    else:
        raise ValueError(f"partition: None, 'interface' or 'interface-noghost', got {partition!r}")
    x = mesh.geometry.x
    s = x[:, 0].copy()
    sf = n_fluid / nr
    x[:, 0] = np.where(s <= sf, s / sf * R_I, R_I + (s - sf) / (1.0 - sf) * (R_O - R_I))
    x[:, 1] *= LENGTH
    return mesh


def tube_case(comm=MPI.COMM_WORLD, n_fluid=4, n_wall=2, n_axial=40, backflow=1.0, partition=None) -> TubeCase:
    mesh = tube_mesh(comm, n_fluid, n_wall, n_axial, partition)
    tol = 1e-9
    ct = tag_cells(mesh, {FLUID: lambda x: x[0] < R_I, WALL: lambda x: x[0] > R_I})
    ft = tag_facets(mesh, {
        INLET: lambda x: (np.abs(x[1]) < tol) & (x[0] < R_I),
        OUTLET: lambda x: (np.abs(x[1] - LENGTH) < tol) & (x[0] < R_I),
        WALL_ENDS: lambda x: ((np.abs(x[1]) < tol) | (np.abs(x[1] - LENGTH) < tol)) & (x[0] > R_I),
        OUTER: lambda x: np.abs(x[0] - R_O) < tol,
        AXIS: lambda x: np.abs(x[0]) < tol,
    })
    amplitude = fem.Constant(mesh, AMPLITUDE)
    speed = fem.Constant(mesh, SPEED)

    def traction(X, t, N):
        ramp = 1.0 - ufl.exp(-t / T_RAMP)
        gauss = ufl.exp(-((X[1] - Z0 - speed * t) / WIDTH) ** 2)
        return amplitude * ramp * gauss * N

    scene = Scene(
        mesh=mesh, cell_tags=ct, facet_tags=ft, axisymmetric=True, name="mini_tube",
        fluid=FluidRegion([FLUID], FLUID_MATERIAL),
        solids=[SolidRegion([WALL], WALL_MATERIAL)],
        open_boundaries=[OpenBoundary([INLET], REFERENCE_STRESS, backflow),
                         OpenBoundary([OUTLET], REFERENCE_STRESS, backflow)],
        loads=[SurfaceLoad([OUTER], traction)],
        dirichlet=[DirichletCondition("velocity", [WALL_ENDS]),
                   DirichletCondition("displacement", [WALL_ENDS]),
                   DirichletCondition("displacement", [INLET, OUTLET]),
                   DirichletCondition("velocity", [AXIS], components=[0]),
                   DirichletCondition("displacement", [AXIS], components=[0])],
    )
    return TubeCase(scene, amplitude, speed)


def tube_problem(comm=MPI.COMM_WORLD, options: SolverOptions | None = None, **mesh_kw):
    case = tube_case(comm, **mesh_kw)
    return MonolithicFSI(case.scene, options), case


def tube_run(steps=4, dt=2e-3, **options):
    """The tube from its steady state over `steps` steps of dt with SolverOptions(**options): (problem, iterations)."""
    pb, _ = tube_problem(options=SolverOptions(**options))
    pb.solve_steady()
    return pb, [pb.step(dt)[0] for _ in range(steps)]


def tube_reference():
    """tube_run converged tightly by full Newton (whole-system LU): the discrete solution to ~1e-12."""
    return tube_run(linear_solver="mumps", reuse_jacobian=False, newton_rtol=1e-12, newton_atol=1e-20,
                    newton_stol=1e-13, newton_max_iterations=40)[0]


def field_errors(pb, ref) -> dict:
    """max |x_f - ref_f| / max |ref_f| per field of two problems on the same mesh."""
    out = {}
    for f in pb.field_names:
        dofs = np.asarray(pb.sub(f).collapse()[1])
        out[f] = np.abs(pb.x.x.array[dofs] - ref.x.x.array[dofs]).max() / np.abs(ref.x.x.array[dofs]).max()
    return out


# --------------------------------------------------------------------------------------------
class Quantities:
    """Parallel-safe quantities of interest of the tube problem (all values identical on all ranks)."""

    def __init__(self, problem: MonolithicFSI, quadrature_degree: int = 8):
        self.pb = pb = problem
        mesh, ops = pb.mesh, pb.ops
        md = {"quadrature_degree": quadrature_degree}
        dx = ufl.Measure("dx", domain=mesh, subdomain_data=pb.scene.cell_tags, metadata=md)
        ds = ufl.Measure("ds", domain=mesh, subdomain_data=pb.scene.facet_tags, metadata=md)
        s = ufl.split(pb.x)
        v, u = s[pb.index["velocity"]], s[pb.index["displacement"]]
        F = ops.identity() + ops.grad(u)
        J = ufl.det(F)
        N = ops.normal()
        n_da = J * ufl.inv(F).T * N
        w = pb.split(pb.x_dot)["displacement"]   # BDF mesh velocity of the last accepted step
        rel = ops.vec(v) - ops.vec(w)
        self.volume_form = fem.form(J * ops.weight * dx(FLUID))
        self.flux_forms = {name: fem.form(ufl.dot(rel, n_da) * ops.weight * ds(tag))
                           for name, tag in (("inlet", INLET), ("outlet", OUTLET))}
        # wall displacement: owned dofs of the collapsed displacement space in wall cells
        self._Vu, _ = pb.W.sub(pb.index["displacement"]).collapse()
        tdim = mesh.topology.dim
        wall_cells = pb.cells([WALL])
        dofs = fem.locate_dofs_topological(self._Vu, tdim, wall_cells)
        self._wall_dofs = dofs[dofs < self._Vu.dofmap.index_map.size_local]

    def _scalar(self, form):
        return self.pb.comm.allreduce(fem.assemble_scalar(form), op=MPI.SUM)

    def volume(self):
        return self._scalar(self.volume_form)

    def flux(self, name):
        """Net outflow (v - w).n da through an open boundary (m^3/s)."""
        return self._scalar(self.flux_forms[name])

    def max_wall_displacement(self):
        u = self.pb.field("displacement")
        vals = u.x.array.reshape(-1, 2)[self._wall_dofs]
        local = float(np.sqrt((vals ** 2).sum(axis=1)).max()) if vals.size else 0.0
        return self.pb.comm.allreduce(local, op=MPI.MAX)


class VolumeFluxObserver(Observer):
    """Records t, V(t), the open-boundary outflows, the BDF coefficients and dt of every step."""

    def __init__(self, quantities: Quantities):
        self.q = quantities
        self.records = {"step": [], "t": [], "volume": [], "inlet": [], "outlet": [], "bdf": [], "dt": []}

    def observe(self, problem, step):
        r = self.records
        r["step"].append(step)
        r["t"].append(problem.time)
        r["volume"].append(self.q.volume())
        if step == 0:   # initial state: at rest (the mesh velocity form is not defined yet)
            r["inlet"].append(0.0)
            r["outlet"].append(0.0)
            r["bdf"].append([0.0, 0.0, 0.0])
            r["dt"].append(0.0)
        else:
            r["inlet"].append(self.q.flux("inlet"))
            r["outlet"].append(self.q.flux("outlet"))
            r["bdf"].append([float(c.value) for c in problem.bdf])
            r["dt"].append(float(problem.dt.value))

    def state(self):
        return {k: list(v) for k, v in self.records.items()}

    def load_state(self, state):
        self.records = {k: list(v) for k, v in state.items()}


class QoIObserver(Observer):
    """Outlet flux, max wall displacement and min ALE Jacobian after every step."""

    def __init__(self, quantities: Quantities):
        self.q = quantities
        self.records = {"t": [], "outlet_flux": [], "max_wall_displacement": [], "min_ale_jacobian": []}

    def observe(self, problem, step):
        if step == 0:
            return
        r = self.records
        r["t"].append(problem.time)
        r["outlet_flux"].append(self.q.flux("outlet"))
        r["max_wall_displacement"].append(self.q.max_wall_displacement())
        r["min_ale_jacobian"].append(problem.min_ale_jacobian())

    def state(self):
        return {k: list(v) for k, v in self.records.items()}

    def load_state(self, state):
        self.records = {k: list(v) for k, v in state.items()}


class FailingFactorisation:
    """A KSP that solves as `ksp` does but reports KSP_DIVERGED_PC_FAILED (-11): a failed factorisation."""

    def __init__(self, ksp):
        self._ksp = ksp

    def __getattr__(self, name):
        return getattr(self._ksp, name)

    def getConvergedReason(self):
        return -11
