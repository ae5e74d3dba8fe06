"""Turek-Hron FSI benchmarks (Turek & Hron 2006, "Proposal for numerical benchmarking of
fluid-structure interaction between an elastic object and laminar incompressible flow") as scenes
of the generic engine: the steady FSI1 and the periodic FSI2 and FSI3 verify the monolithic ALE coupling.

Geometry (SI): channel [0, 2.5] x [0, 0.41]; rigid cylinder of radius 0.05 centred at (0.2, 0.2);
elastic flag of thickness 0.02 clamped on the cylinder's downstream side, right end at x = 0.6,
y in [0.19, 0.21]; point A = (0.6, 0.2) at the middle of the flag tip.
FSI1: rho_f = 1e3, nu_f = 1e-3, rho_s = 1e3, nu_s = 0.4, mu_s = 0.5e6 (St Venant-Kirchhoff),
mean inflow U = 0.2 (Re = 20); steady state.
FSI2: rho_s = 1e4, mu_s = 0.5e6, U = 1 (Re = 100); FSI3: rho_s = 1e3, mu_s = 2e6, U = 2 (Re = 200); the
inflow ramped by (1 - cos(pi t / 2)) / 2 for t < 2 s; periodic regime (mean, amplitude, frequency).

Quantities: displacement of A, drag and lift on the whole obstacle (cylinder + flag) from the fluid
stress, by default as the variational (residual) force F_i = -R_fluid(v, p, u; phi_i), with phi_i = e_i
on the obstacle boundary velocity dofs and 0 elsewhere (superconvergent; Babuska-Miller), and as a
cross-check the boundary integral of the fluid traction. The transient runs of FSI2 and FSI3 and their
periodic statistics: `ureterfsi.scenes.turek_hron_transient`.
"""
from __future__ import annotations

import hashlib
import math
import os
import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path

import gmsh
import numpy as np
import ufl
from dolfinx import fem
from dolfinx.io import gmshio
from mpi4py import MPI

from ureterfsi.fsi import (DirichletCondition, FluidRegion, LinearElastic, MonolithicFSI, NewtonDivergence,
                           NewtonianFluid, OpenBoundary, Scene, SolidRegion, SolverOptions)
from ureterfsi.fsi import physics
from ureterfsi.fsi.probes import PointProbe


# --- geometry and tags --------------------------------------------------------------------------
@dataclass(frozen=True)
class Geometry:
    length: float = 2.5
    height: float = 0.41
    centre: tuple = (0.2, 0.2)
    radius: float = 0.05
    flag_length: float = 0.35          # nominal: the flag's left end lies on the cylinder
    flag_thickness: float = 0.02
    flag_end: float = 0.6              # x of the flag tip

    @property
    def point_a(self):
        return (self.flag_end, self.centre[1])


@dataclass(frozen=True)
class Tags:
    fluid: int = 1
    flag: int = 2
    inlet: int = 11
    outlet: int = 12
    walls: int = 13                    # channel walls y = 0 and y = H
    cylinder: int = 14                 # cylinder wall wetted by the fluid
    clamp: int = 15                    # the flag's end face attached to the cylinder (clamped)
    interface: int = 16                # fluid-flag interface (flag top, bottom and tip)


TAGS = Tags()
GEOMETRY = Geometry()


@dataclass(frozen=True)
class FSI1:
    rho_f: float = 1.0e3
    nu_f: float = 1.0e-3
    rho_s: float = 1.0e3
    nu_s: float = 0.4
    mu_s: float = 0.5e6
    mean_inflow: float = 0.2

    @property
    def fluid(self) -> NewtonianFluid:
        return NewtonianFluid(density=self.rho_f, dynamic_viscosity=self.rho_f * self.nu_f)

    @property
    def solid(self) -> LinearElastic:
        return LinearElastic(youngs_modulus=2.0 * self.mu_s * (1.0 + self.nu_s), poisson_ratio=self.nu_s,
                             density=self.rho_s, kinematics="st_venant_kirchhoff")


@dataclass(frozen=True)
class FSI2(FSI1):
    rho_s: float = 1.0e4
    mu_s: float = 0.5e6
    mean_inflow: float = 1.0


@dataclass(frozen=True)
class FSI3(FSI1):
    rho_s: float = 1.0e3
    mu_s: float = 2.0e6
    mean_inflow: float = 2.0


# Turek & Hron 2006, Table "FSI1" (finest level)
REFERENCE_FSI1 = {"ux_A": 0.0227e-3, "uy_A": 0.8209e-3, "drag": 14.295, "lift": 0.7638}
RAMP_TIME = 2.0          # s, the benchmark's inflow ramp

# choice: element sizes at refinement 1: H_NEAR on the cylinder and the flag boundary, growing
# linearly to H_FAR at distance SIZE_DISTANCE; sizes scale with 1/refinement.
H_NEAR = 0.008
H_FAR = 0.04
SIZE_DISTANCE = 0.25


def _mesh_sizes(refinement: float):
    return H_NEAR / refinement, H_FAR / refinement


def _cache_dir() -> Path:
    base = os.environ.get("URETERFSI_CACHE") or os.path.join(tempfile.gettempdir(), "ureterfsi-cache")
    return Path(base) / "turek_hron"


def write_mesh(path, refinement: float = 1.0, geom: Geometry = GEOMETRY, tags: Tags = TAGS) -> dict:
    """Mesh the benchmark with gmsh OCC (triangles, first order) and write it to `path` (msh 4.1).
    Call on one rank. Returns counts of the physical groups."""
    h_near, h_far = _mesh_sizes(refinement)
    L, H, (cx, cy), r = geom.length, geom.height, geom.centre, geom.radius
    y0, y1 = cy - 0.5 * geom.flag_thickness, cy + 0.5 * geom.flag_thickness
    gmsh.initialize()
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.model.add("turek_hron")
        occ = gmsh.model.occ
        channel = occ.addRectangle(0.0, 0.0, 0.0, L, H)
        disk = occ.addDisk(cx, cy, 0.0, r, r)
        flag = occ.addRectangle(cx, y0, 0.0, geom.flag_end - cx, y1 - y0)
        flag_cut, _ = occ.cut([(2, flag)], [(2, disk)], removeTool=False)
        domain, _ = occ.cut([(2, channel)], [(2, disk)])
        occ.fragment(domain, flag_cut)
        occ.synchronize()

        surfaces = [t for _, t in gmsh.model.getEntities(2)]
        flag_s, fluid_s = [], []
        for s in surfaces:
            xc, yc, _ = occ.getCenterOfMass(2, s)
            (flag_s if (cx < xc < geom.flag_end and y0 < yc < y1) else fluid_s).append(s)
        if len(flag_s) != 1 or len(fluid_s) != 1:
            raise RuntimeError(f"Turek-Hron geometry: expected one fluid and one flag surface, got "
                               f"{fluid_s} and {flag_s}")
        flag_curves = {abs(t) for _, t in gmsh.model.getBoundary([(2, flag_s[0])], oriented=False)}
        fluid_curves = {abs(t) for _, t in gmsh.model.getBoundary([(2, fluid_s[0])], oriented=False)}
        groups = {k: [] for k in ("inlet", "outlet", "walls", "cylinder", "clamp", "interface")}
        eps = 1e-8
        for c in sorted(flag_curves | fluid_curves):
            lo, hi = gmsh.model.getParametrizationBounds(1, c)
            x, y, _ = gmsh.model.getValue(1, c, [0.5 * (lo[0] + hi[0])])
            on_circle = abs(math.hypot(x - cx, y - cy) - r) < 1e-6
            if c in flag_curves and c in fluid_curves:
                groups["interface"].append(c)
            elif on_circle:
                groups["clamp" if c in flag_curves else "cylinder"].append(c)
            elif abs(x) < eps:
                groups["inlet"].append(c)
            elif abs(x - L) < eps:
                groups["outlet"].append(c)
            elif abs(y) < eps or abs(y - H) < eps:
                groups["walls"].append(c)
            else:
                raise RuntimeError(f"Turek-Hron geometry: unclassified curve {c} through ({x}, {y})")
        for name, curves in groups.items():
            if not curves:
                raise RuntimeError(f"Turek-Hron geometry: no curve for {name}")
            gmsh.model.addPhysicalGroup(1, curves, getattr(tags, name))
            gmsh.model.setPhysicalName(1, getattr(tags, name), name)
        gmsh.model.addPhysicalGroup(2, fluid_s, tags.fluid)
        gmsh.model.setPhysicalName(2, tags.fluid, "fluid")
        gmsh.model.addPhysicalGroup(2, flag_s, tags.flag)
        gmsh.model.setPhysicalName(2, tags.flag, "flag")

        # sizes: fine on the obstacle (cylinder + flag), linear growth into the channel
        fld = gmsh.model.mesh.field
        dist = fld.add("Distance")
        fld.setNumbers(dist, "CurvesList", groups["cylinder"] + groups["clamp"] + groups["interface"])
        fld.setNumber(dist, "NumPointsPerCurve", 200)
        thr = fld.add("Threshold")
        fld.setNumber(thr, "InField", dist)
        fld.setNumber(thr, "SizeMin", h_near)
        fld.setNumber(thr, "SizeMax", h_far)
        fld.setNumber(thr, "DistMin", 0.0)
        fld.setNumber(thr, "DistMax", SIZE_DISTANCE)
        fld.setAsBackgroundMesh(thr)
        gmsh.option.setNumber("Mesh.MeshSizeExtendFromBoundary", 0)
        gmsh.option.setNumber("Mesh.MeshSizeFromPoints", 0)
        gmsh.option.setNumber("Mesh.MeshSizeFromCurvature", 0)
        gmsh.option.setNumber("Mesh.Algorithm", 6)          # Frontal-Delaunay
        gmsh.option.setNumber("Mesh.MshFileVersion", 4.1)
        gmsh.option.setNumber("Mesh.SaveAll", 0)
        gmsh.model.mesh.generate(2)
        path = Path(path)
        path.parent.mkdir(parents=True, exist_ok=True)
        part = path.with_name(f".{path.stem}.{os.getpid()}.part.msh")
        gmsh.write(str(part))
        os.replace(part, path)
        _, elem_tags, _ = gmsh.model.mesh.getElements(2)
        return {"triangles": int(sum(len(e) for e in elem_tags)), "h_near": h_near, "h_far": h_far}
    finally:
        gmsh.finalize()


def read_mesh(path, comm=MPI.COMM_WORLD, gdim: int = 2):
    """(mesh, cell_tags, facet_tags) from a .msh file.

    dolfinx 0.5.2's gmshio.read_from_msh is broken (it finalizes gmsh and returns an undefined name
    on the reading rank), so this does what it means to: merge on rank 0, model_to_mesh on all ranks."""
    if comm.rank == 0:
        gmsh.initialize()
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.model.add("mesh from file")
        gmsh.merge(str(path))
    try:
        return gmshio.model_to_mesh(gmsh.model, comm, 0, gdim=gdim)
    finally:
        if comm.rank == 0:
            gmsh.finalize()


def build_mesh(refinement: float = 1.0, comm=MPI.COMM_WORLD, cache_dir=None):
    """Mesh at the given refinement (sizes H_NEAR/refinement .. H_FAR/refinement), cached as .msh."""
    key = hashlib.sha1(repr((refinement, H_NEAR, H_FAR, SIZE_DISTANCE, GEOMETRY, TAGS, 2)).encode()).hexdigest()[:12]
    path = Path(cache_dir or _cache_dir()) / f"turek_hron_r{refinement:g}_{key}.msh"
    if comm.rank == 0 and not path.exists():
        write_mesh(path, refinement)
    comm.barrier()
    return read_mesh(path, comm, gdim=2)


# --- scene ----------------------------------------------------------------------------------------
@dataclass
class ParabolicInflow:
    """v(0, y) = amplitude * r(t) * 1.5 U y (H - y) / (H/2)^2 e_x; `amplitude` is mutable (continuation);
    r(t) = (1 - cos(pi t / T)) / 2 for t < T = ramp_time, else 1 (no ramp if ramp_time = 0)."""
    mean_velocity: float
    height: float = GEOMETRY.height
    amplitude: float = 1.0
    ramp_time: float = 0.0

    def ramp(self, t) -> float:
        if t >= self.ramp_time:
            return 1.0
        return 0.5 * (1.0 - math.cos(math.pi * t / self.ramp_time))

    def __call__(self, x, t):
        H = self.height
        vx = self.amplitude * self.ramp(t) * 1.5 * self.mean_velocity * x[1] * (H - x[1]) / (0.5 * H) ** 2
        return np.vstack([vx, np.zeros_like(vx)])


def make_scene(mesh, cell_tags, facet_tags, params: FSI1 = FSI1(), tags: Tags = TAGS, backflow: float = 0.0,
               ramp_time: float = 0.0, body_forces=()):
    """The scene of `params` on a tagged mesh. Returns (scene, inflow); inflow.amplitude scales the inlet."""
    inflow = ParabolicInflow(params.mean_inflow, ramp_time=ramp_time)
    fixed = [tags.inlet, tags.outlet, tags.walls, tags.cylinder, tags.clamp]
    scene = Scene(
        mesh=mesh, cell_tags=cell_tags, facet_tags=facet_tags,
        fluid=FluidRegion([tags.fluid], params.fluid),
        solids=[SolidRegion([tags.flag], params.solid)],
        open_boundaries=[OpenBoundary([tags.outlet], normal_stress=0.0, backflow=backflow)],
        dirichlet=[DirichletCondition("velocity", [tags.inlet], inflow),
                   DirichletCondition("velocity", [tags.walls, tags.cylinder, tags.clamp]),
                   DirichletCondition("displacement", fixed)],
        body_forces=list(body_forces), name=f"turek_hron_{type(params).__name__.lower()}")
    return scene, inflow


# --- quantities -------------------------------------------------------------------------------------
def point_value(f: fem.Function, point) -> np.ndarray:
    """Value of f at a point, on every rank (probes.PointProbe)."""
    value = PointProbe(f.function_space.mesh, np.asarray([point], dtype=float))(f)[0]
    if np.isnan(value).any():
        raise ValueError(f"point {point} lies outside the mesh")
    return value


class ObstacleForces:
    """Drag and lift (per unit depth) of the fluid on the obstacle (cylinder + flag)."""

    def __init__(self, problem: MonolithicFSI, tags: Tags = TAGS):
        pb, mesh = problem, problem.mesh
        self.problem = pb
        fluid = pb.scene.fluid.material
        ops = pb.ops
        fdim = mesh.topology.dim - 1

        # the state and the BDF time derivative of the last accepted step (zero after a steady solve)
        X, Xdot = pb.split(), pb.split(pb.x_dot)
        v, p, u = X["velocity"], X["pressure"], X["displacement"]
        dx_f = pb.dx(tuple(pb.fluid_tags))

        # variational force: phi_i = e_i at velocity dofs on the obstacle boundary, 0 elsewhere
        V, _ = pb.sub("velocity").collapse()
        ft = pb.scene.facet_tags
        facets = np.unique(np.concatenate([ft.find(t) for t in (tags.cylinder, tags.clamp, tags.interface)]))
        dofs = fem.locate_dofs_topological(V, fdim, facets.astype(np.int32))
        bs = V.dofmap.index_map_bs
        self._forms = []
        for i in range(mesh.geometry.dim):
            phi = fem.Function(V)
            phi.x.array[dofs * bs + i] = 1.0
            phi.x.scatter_forward()
            R = physics.fluid_ale_residual(ops, fluid, v, p, u, Xdot["velocity"], Xdot["displacement"],
                                           phi, 0.0 * p, dx_f)
            for ob in pb.scene.open_boundaries:       # zero here unless an obstacle touches one
                R += physics.open_boundary_residual(ops, fluid, ob.normal_stress, ob.backflow, v, u,
                                                    Xdot["displacement"], phi, pb.ds(tuple(ob.tags)))
            self._forms.append(fem.form(-R))
            setattr(self, f"_phi{i}", phi)

        # boundary integral of the fluid traction, sigma J F^-T N dA, over the wetted cylinder (exterior
        # facets) and the fluid side of the interface (interior facets; side picked by a fluid indicator)
        F = physics.deformation_gradient(ops, u)
        sigma = physics.fluid_cauchy_stress(ops, fluid, v, p, F)
        N = ufl.FacetNormal(mesh)
        Q = fem.FunctionSpace(mesh, ("DG", 0))
        chi = fem.Function(Q)
        chi.x.array[Q.dofmap.list.array[pb.cells(pb.fluid_tags)]] = 1.0   # DG0: one dof per cell
        traction = lambda s: ufl.det(F(s)) * sigma(s) * ufl.inv(F(s)).T * N(s)   # noqa: E731
        dS = ufl.Measure("dS", domain=mesh, subdomain_data=ft, metadata=pb.dx.metadata())
        self._bforms = []
        for i in range(mesh.geometry.dim):
            t_ext = ufl.det(F) * sigma * ufl.inv(F).T * N
            # the obstacle's outward normal is minus the fluid's
            form = (-t_ext[i] * pb.ds(tags.cylinder)
                    - (chi("+") * traction("+")[i] + chi("-") * traction("-")[i]) * dS(tags.interface))
            self._bforms.append(fem.form(form))

    def _assemble(self, forms):
        comm = self.problem.comm
        return np.array([comm.allreduce(fem.assemble_scalar(f), MPI.SUM) for f in forms])

    def variational(self) -> np.ndarray:
        """(drag, lift) = -R_fluid(phi_x), -R_fluid(phi_y)."""
        return self._assemble(self._forms)

    def boundary(self) -> np.ndarray:
        """(drag, lift) from the boundary integral of the fluid traction."""
        return self._assemble(self._bforms)


# --- the benchmark ----------------------------------------------------------------------------------
@dataclass
class FSI1Result:
    refinement: float
    dofs: int
    cells: int
    newton_iterations: int
    continuation: list
    wall_time: float
    setup_time: float
    solve_time: float
    ux_A: float
    uy_A: float
    drag: float
    lift: float
    drag_boundary: float
    lift_boundary: float
    min_ale_jacobian: float
    errors: dict = field(default_factory=dict)

    def relative_errors(self, reference=REFERENCE_FSI1) -> dict:
        return {k: abs(getattr(self, k) - ref) / abs(ref) for k, ref in reference.items()}


def solve_steady_with_continuation(problem: MonolithicFSI, inflow: ParabolicInflow,
                                   amplitudes=(1.0,), fallback=(0.25, 0.5, 0.75, 1.0)):
    """Steady solve at full inflow; on Newton failure restart from rest and ramp the amplitude."""
    total, used = 0, []
    for plan in (amplitudes, fallback):
        problem.x.x.array[:] = 0.0
        try:
            for a in plan:
                inflow.amplitude = a
                its, _ = problem.solve_steady()
                total += its
                used.append((a, its))
            return total, used
        except NewtonDivergence as err:
            used.append((inflow.amplitude, f"failed: {err}"))
            total += len(err.history) - 1
    raise NewtonDivergence(f"steady FSI1 failed even with continuation {fallback}: {used}", [])


def run_fsi1(refinement: float = 1.0, comm=MPI.COMM_WORLD, options: SolverOptions | None = None,
             params: FSI1 = FSI1()) -> FSI1Result:
    t0 = time.perf_counter()
    mesh, ct, ft = build_mesh(refinement, comm)
    scene, inflow = make_scene(mesh, ct, ft, params)
    problem = MonolithicFSI(scene, options or SolverOptions())
    forces = ObstacleForces(problem)
    t1 = time.perf_counter()
    its, used = solve_steady_with_continuation(problem, inflow)
    t2 = time.perf_counter()
    uA = point_value(problem.field("displacement"), GEOMETRY.point_a)
    drag, lift = forces.variational()
    drag_b, lift_b = forces.boundary()
    ncells = comm.allreduce(mesh.topology.index_map(2).size_local, MPI.SUM)
    dofs = problem.W.dofmap.index_map.size_global * problem.W.dofmap.index_map_bs
    res = FSI1Result(refinement, dofs, ncells, its, used, time.perf_counter() - t0, t1 - t0, t2 - t1,
                     float(uA[0]), float(uA[1]), float(drag), float(lift), float(drag_b), float(lift_b),
                     problem.min_ale_jacobian())
    res.errors = res.relative_errors()
    return res
