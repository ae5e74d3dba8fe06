"""One-way coupled rung of the fidelity ladder: wall -> urine -> stent.

The fully coupled rung (ureterfsi.study.coupled) solves wall, urine and stent in one Newton system. This rung
solves them in sequence, each with the engine's own physics blocks:

1. **wall**: the ureter wall alone in the axisymmetric r-z formulation (exact for the wall of every
   model: the geometry and the load are axisymmetric), Mooney-Rivlin with inertia, travelling
   Gaussian load (ureterfsi.scenes.wall_rz.WallModel); its inner- and outer-surface motion is recorded
   at every step. Neglected: the urine pressure on the inner wall, |p - p_ref| against the 5e4 Pa load
   (measured in the fluid step and stored as `one_way_max_wall_pressure_deviation`).
2. **urine**: the fluid alone on the fluid part of the 3D mesh, ALE, with the recorded inner-wall
   motion prescribed (velocity and mesh displacement) and the stent held rigid; the mesh moves by a
   closed-form radial blend of the wall motion (radial_blend) or by a segregated extension problem.
3. **stent**: quasi-static linear elasticity on the stent part of the mesh, loaded by the urine's
   consistent nodal reaction forces on the fluid-stent interface (the residual of the fluid equations
   at the interface velocity dofs); stiffness matrix factorised once. Neglected: the stent deformation
   in the fluid domain (`one_way_max_stent_displacement` against the hole diameter) and the stent
   inertia (first bending frequency of the clamped 50 mm silicone tube ~46 Hz against the ~2 Hz of
   the load: dynamic amplification < 0.2 %).
"""
from __future__ import annotations

import dataclasses
import logging
import math
import time as _time
from dataclasses import dataclass
from functools import partial

import numpy as np
import ufl
import xarray as xr
from dolfinx import fem
from dolfinx.fem import petsc as fem_petsc
from mpi4py import MPI
from petsc4py import PETSc

from ureterfsi.mesh import tags
from ureterfsi.study.fields import oneway_parts
from ..fsi import Observer, SolveFailure, SolverOptions, TimeIntegrator, TimeSettings, physics
from ..fsi.ale_jacobian import ALEJacobian
from ..fsi.operators import Operators
from ..fsi.constraints import dirichlet_bcs
from ..fsi.problem import MonolithicFSI
from ..fsi.scene import DirichletCondition
from ..fsi.submesh import SubDomain, extract
from ureterfsi.mesh.geometry import StentModel, UreterGeometry
from ureterfsi.fsi.probes import CellField, PointProbe, von_mises
from ureterfsi.data.checked import BadFile, Contract, open_netcdf
from ..config import wall_sections
from ureterfsi.data.cf import WALL_MOTION_VARIABLES, attach, write_netcdf
from ureterfsi.data.provenance import config_hash, provenance_attrs
from ..scenes.ureter import materials, ureter_fluid_scene
from ..scenes.wall_rz import WallModel
from . import pipeline
from .options import RunSpec, solver_options
from .probes import N_LINE, UreterProbes

log = logging.getLogger("ureterfsi.study.oneway")


# ------------------------------------------------------------------------------------------------
# 1. wall
# ------------------------------------------------------------------------------------------------
# what WallHistory.from_dataset reads in a wall-motion file (rule wall_motion, write_wall_motion)
WALL_MOTION = Contract("wall-motion file", attrs=("wall_config_hash",),
                       variables=("time", "z_inner", "z_outer", "inner_radial_displacement",
                                  "inner_axial_displacement", "inner_radial_velocity", "inner_axial_velocity",
                                  "outer_radial_displacement"), units=WALL_MOTION_VARIABLES)

@dataclass
class WallHistory:
    """Recorded motion of the ureter wall surfaces (r-z solve): arrays (time, z)."""
    time: np.ndarray
    z_inner: np.ndarray
    inner_ur: np.ndarray
    inner_uz: np.ndarray
    inner_vr: np.ndarray
    inner_vz: np.ndarray
    z_outer: np.ndarray
    outer_ur: np.ndarray
    wall_time: float = 0.0

    def _at(self, field, zs, z, t):
        """Linear interpolation in time between recorded steps and in z along the surface."""
        k = int(np.clip(np.searchsorted(self.time, t), 1, len(self.time) - 1))
        t0, t1 = self.time[k - 1], self.time[k]
        a = 0.0 if t1 == t0 else float(np.clip((t - t0) / (t1 - t0), 0.0, 1.0))
        row = (1.0 - a) * field[k - 1] + a * field[k]
        return np.interp(z, zs, row)

    def inner(self, z, t):
        """(u_r, u_z, v_r, v_z) of the inner wall at axial positions z and time t."""
        return self.inner_displacement(z, t) + tuple(self._at(f, self.z_inner, z, t)
                                                     for f in (self.inner_vr, self.inner_vz))

    def inner_displacement(self, z, t):
        """(u_r, u_z) of the inner wall at axial positions z and time t."""
        return tuple(self._at(f, self.z_inner, z, t) for f in (self.inner_ur, self.inner_uz))

    def outer_radial(self, z, t):
        return self._at(self.outer_ur, self.z_outer, z, t)

    def to_dataset(self, cfg: dict) -> xr.Dataset:
        """CF-annotated dataset of the recorded motion, with provenance and the hash of the configuration
        sections the wall solve reads (`wall_config_hash`, checked by from_dataset)."""
        ds = attach(xr.Dataset(      # rows are times; written time last (CF §2.4)
            {"inner_radial_displacement": (("z_inner", "time"), np.asarray(self.inner_ur).T),
             "inner_axial_displacement": (("z_inner", "time"), np.asarray(self.inner_uz).T),
             "inner_radial_velocity": (("z_inner", "time"), np.asarray(self.inner_vr).T),
             "inner_axial_velocity": (("z_inner", "time"), np.asarray(self.inner_vz).T),
             "outer_radial_displacement": (("z_outer", "time"), np.asarray(self.outer_ur).T)},
            coords={"time": ("time", self.time), "z_inner": ("z_inner", self.z_inner),
                    "z_outer": ("z_outer", self.z_outer)}), WALL_MOTION_VARIABLES)
        ds.attrs.update(provenance_attrs(cfg, model="wall", fidelity="one_way", wall_solve_time_s=round(self.wall_time, 2),
                                         wall_config_hash=config_hash(wall_sections(cfg))))
        ds.attrs["Conventions"] = "CF-1.8"
        ds.attrs["title"] = "ureterfsi one-way rung, step 1: the ureter wall alone (r-z), surface motion"
        return ds

    @classmethod
    def from_dataset(cls, ds: xr.Dataset, cfg: dict, end: float, dt: float) -> "WallHistory":
        """The recorded motion of a wall_motion dataset, refused unless it was computed from the same wall
        configuration with the same time step and reaches `end`. Shorter steps where the wall solve halved one
        (TimeIntegrator: a failed step retried with dt/2) are accepted as long as every step time k dt of the run
        is recorded: the run then reads the wall at its own times."""
        want = config_hash(wall_sections(cfg))
        source = ds.encoding.get("source", "wall motion")
        if ds.attrs.get("wall_config_hash") != want:
            raise BadFile(source, f"wall motion computed from another configuration "
                                  f"(wall_config_hash {ds.attrs.get('wall_config_hash')} != {want})")
        t = ds["time"].values
        steps = np.diff(t)
        tol = 1e-9 * max(dt, end)
        run_times = dt * np.arange(int(round(end / dt)) + 1)
        recorded = t.size >= 2 and steps.max() <= dt + tol and all(np.abs(t - tk).min() <= tol for tk in run_times)
        if not recorded or t[-1] < end - tol:
            raise BadFile(source, f"wall motion covers [0, {t[-1] if t.size else 0:g}] s in steps "
                                  f"{steps.min() if steps.size else 0:g}-{steps.max() if steps.size else 0:g} s; "
                                  f"this run needs [0, {end:g}] s in steps of {dt:g} s")
        field = lambda name: ds[name].transpose("time", ...).values   # noqa: E731  (written time last, CF §2.4)
        return cls(t, ds["z_inner"].values, field("inner_radial_displacement"),
                   field("inner_axial_displacement"), field("inner_radial_velocity"),
                   field("inner_axial_velocity"), ds["z_outer"].values, field("outer_radial_displacement"),
                   float(ds.attrs.get("wall_solve_time_s", 0.0)))



class _SurfaceRecorder(Observer):
    """Observer of the r-z wall solve: inner/outer surface displacement and velocity each step."""

    def __init__(self, model):
        pb = model.problem
        self.pb = pb
        self.U, self.umap = pb.sub("displacement").collapse()
        self.V, self.vmap = pb.sub("velocity").collapse()
        xu, xv = self.U.tabulate_dof_coordinates(), self.V.tabulate_dof_coordinates()

        def nodes(space, coords, facet_tag):
            idx = model.surface_dofs(space, facet_tag)
            return idx[np.argsort(coords[idx, 1])]

        self.iu, self.iv = nodes(self.U, xu, tags.FLUID_URETER), nodes(self.V, xv, tags.FLUID_URETER)
        self.ou = nodes(self.U, xu, tags.URETER_OUTER)
        self.z_inner, self.z_outer = xu[self.iu, 1], xu[self.ou, 1]
        assert np.allclose(self.z_inner, xv[self.iv, 1])
        self.rows = {k: [] for k in ("time", "iur", "iuz", "ivr", "ivz", "our")}

    def observe(self, problem, step):
        x = self.pb.x.x.array
        u = x[self.umap].reshape(-1, 2)
        v = x[self.vmap].reshape(-1, 2)
        r = self.rows
        r["time"].append(problem.time)
        r["iur"].append(u[self.iu, 0].copy())
        r["iuz"].append(u[self.iu, 1].copy())
        r["ivr"].append(v[self.iv, 0].copy())
        r["ivz"].append(v[self.iv, 1].copy())
        r["our"].append(u[self.ou, 0].copy())

    def state(self):
        return {}

    def load_state(self, state):
        pass


def wall_history(cfg: dict, end: float, dt: float, nr: int = 4) -> WallHistory:
    """Transient r-z wall-alone solve over [0, end] with step dt (from rest, load ramped)."""
    t0 = _time.perf_counter()
    model = WallModel(cfg, nr=nr, travelling=True,
                      options=SolverOptions(newton_rtol=1e-10, newton_atol=1e-12, newton_max_iterations=25,
                                            reuse_jacobian=True, reuse_contraction=0.3,
                                            predictor=cfg["solver"]["predictor"]))
    rec = _SurfaceRecorder(model)
    TimeIntegrator(model.problem, TimeSettings(end=end, dt=dt, output_times=cfg["time"]["probe_times"],
                                               max_halvings=cfg["solver"]["max_step_halvings"]),
                   observers=[rec]).run()
    r = {k: np.asarray(v) for k, v in rec.rows.items()}
    hist = WallHistory(r["time"], rec.z_inner, r["iur"], r["iuz"], r["ivr"], r["ivz"], rec.z_outer, r["our"],
                       _time.perf_counter() - t0)
    log.info("wall (r-z, %d x %d cells, %d steps): max outer radial displacement %.4e m, %.1f s",
             model.nr, model.nz, len(hist.time) - 1, hist.outer_ur.max(), hist.wall_time)
    return hist


class RecordedWall:
    """Outer-wall radial displacement along the probe line from the recorded wall motion."""

    def __init__(self, history: WallHistory, z: np.ndarray):
        self.history, self.z = history, z

    def radial_displacement(self, time: float) -> np.ndarray:
        return self.history.outer_radial(self.z, time)


# ------------------------------------------------------------------------------------------------
# 2. urine: boundary data of the fluid-alone scene
# ------------------------------------------------------------------------------------------------
def inner_wall_motion(history: WallHistory, axisymmetric: bool):
    """(displacement(x, t), velocity(x, t)) callables of the inner wall for DirichletConditions: the
    r-z motion mapped to 3D, u = u_r e_r + u_z e_z (e_r = (x, y)/R)."""

    def field(x, t, which):
        ur, uz, vr, vz = history.inner(x[1] if axisymmetric else x[2], t)
        a, b = (ur, uz) if which == "u" else (vr, vz)
        if axisymmetric:
            return np.vstack([a, b])
        R = np.maximum(np.hypot(x[0], x[1]), 1e-12)
        return np.vstack([a * x[0] / R, a * x[1] / R, b])

    return (lambda x, t: field(x, t, "u")), (lambda x, t: field(x, t, "v"))


def radial_blend(history: WallHistory, r_still: float, r_wall, axisymmetric: bool, x_still: float = 0.0):
    """Algebraic ALE map of the urine domain, a callable (x, t): the inner-wall motion blended linearly in
    radius, d(x, t) = w(r, z) (u_r(z, t) e_r + u_z(z, t) e_z), w = clip((rho - r_still) / (t_w - r_still), 0, 1),
    rho the distance from the stent axis (x_still, 0) (the ureter axis r unless the stent is offset) and t_w the
    distance from it to the reference inner wall r_wall(z) along the same ray, t_w = -c.e + sqrt((c.e)^2 - |c|^2 +
    r_wall^2), c = (x_still, 0), e the ray's direction (t_w = r_wall(z) for a coaxial stent); r_wall(z) the
    reference inner-wall radius (UreterGeometry.inner_radius: constant, or narrowed by a stricture).

    r_still: the radius inside which the mesh stays still (the rigid stent's outer surface; 0 without a
    stent, where w e_r = x / r_wall stays smooth on the axis). The stent lumen and the side holes do not
    move, the annulus stretches uniformly in r. Exact on the wall (w = 1), on the stent (w = 0), on the
    mirror planes (e_r lies in them) and on the clamped end faces (u = 0 there)."""

    def field(x, t):
        r, z = (x[0], x[1]) if axisymmetric else (np.hypot(x[0], x[1]), x[2])
        ur, uz = history.inner_displacement(z, t)
        if x_still:
            rho = np.hypot(x[0] - x_still, x[1])
            ce = x_still * (x[0] - x_still) / np.maximum(rho, 1e-300)
            t_wall = -ce + np.sqrt(ce**2 - x_still**2 + r_wall(z) ** 2)
            w = np.clip((rho - r_still) / (t_wall - r_still), 0.0, 1.0)
        else:
            w = np.clip((r - r_still) / (r_wall(z) - r_still), 0.0, 1.0)
        if axisymmetric:
            return np.vstack([w * ur, w * uz])
        wr = w * ur / np.maximum(r, 1e-300)
        return np.vstack([wr * x[0], wr * x[1], w * uz])

    return field


class MeshMotionRefused(SolveFailure):
    """Both ALE maps of a one-way urine solve are predicted to fall below solver.one_way_auto_min_jacobian over the
    recorded wall motion: the point is refused before the solve (rather than stopping mid-run, or running on a mesh
    squeezed at the place its results come from)."""


@dataclass(frozen=True)
class JacobianMinimum:
    """The minimum Jacobian of an ALE map over a set of times (-inf where it is not finite): `value` at `time` (s), at
    the reference vertex `where` (x, y, z) (m; r-z: (r, z, nan))."""
    value: float
    time: float
    where: tuple

    def text(self) -> str:
        axes, xyz = ("(r, z)", self.where[:2]) if math.isnan(self.where[2]) else ("(x, y, z)", self.where)
        return f"{self.value:.3g} at t = {self.time:g} s, {axes} = ({', '.join(f'{c:.3e}' for c in xyz)}) m"


NO_MINIMUM = JacobianMinimum(math.nan, math.nan, (math.nan,) * 3)


@dataclass
class MeshMotionChoice:
    """The one-way urine solve's ALE map: `used` (algebraic | extension) by `rule` (solver.one_way_mesh_motion);
    under "auto" the predicted minimum Jacobians of the algebraic map (`algebraic`) and, where that one falls below
    solver.one_way_auto_min_jacobian, of the extension (`extension`) over the recorded wall motion (NO_MINIMUM where
    not predicted)."""
    rule: str
    used: str
    algebraic: JacobianMinimum = NO_MINIMUM
    extension: JacobianMinimum = NO_MINIMUM


def _earliest_minimum(minimum_at, fill, times, axisymmetric: bool) -> JacobianMinimum:
    """The smallest minimum_at() -> (J, (x, y, z)) after fill(t) for each of `times`; the earliest time of a tie."""
    best = (math.inf, math.nan, (math.nan,) * 3)
    for t in times:
        fill(float(t))
        value, where = minimum_at()
        best = min(best, (value, float(t), (where[0], where[1], math.nan) if axisymmetric else where),
                   key=lambda item: item[0])
    return JacobianMinimum(*best)


def map_min_jacobian(d: fem.Function, fill, times, axisymmetric: bool) -> JacobianMinimum:
    """The minimum over `times` of det(I + Grad d), d set by fill(t) for each time, at the vertices of every cell of
    d's mesh (fsi.ale_jacobian.ALEJacobian, the solver's inversion guard); the earliest time of a tie."""
    mesh = d.function_space.mesh
    cells = np.arange(mesh.topology.index_map(mesh.topology.dim).size_local, dtype=np.int32)
    return _earliest_minimum(ALEJacobian(Operators(mesh, axisymmetric), d, cells).minimum_at, fill, times,
                             axisymmetric)


def predicted_min_jacobian(pb: MonolithicFSI, times, axisymmetric: bool) -> JacobianMinimum:
    """map_min_jacobian of the segregated mesh motion of `pb` at `times` before its run: the prescribed map with the
    Dirichlet values set on top, or the extension solved from them (a linear problem given the recorded wall motion;
    its LU factor is the run's), i.e. the run's own map at those times, measured by the run's own inversion guard
    (pb.min_ale_jacobian_at: every cell of the fluid-alone problem is a fluid cell)."""
    with pb.mesh_motion_preview() as at:
        return _earliest_minimum(pb.min_ale_jacobian_at, at, times, axisymmetric)


def fluid_problem(cfg: dict, mesh, cell_tags, facet_tags, history: WallHistory, axisymmetric: bool):
    """(problem, fluid submesh, MeshMotionChoice): the urine alone on the fluid part of the mesh, ALE, the recorded
    inner-wall motion prescribed, the stent rigid, the mesh motion segregated (step 2 of the rung): the radial
    blend (`solver.one_way_mesh_motion: algebraic`), the extension problem (`extension`), or (`auto`) the blend
    unless its predicted minimum Jacobian over the recorded wall motion falls below
    `solver.one_way_auto_min_jacobian`, then the extension unless its own falls below it too: MeshMotionRefused."""
    fluid = extract(mesh, cell_tags, facet_tags, [tags.FLUID])
    u_wall, v_wall = inner_wall_motion(history, axisymmetric)
    rule = cfg["solver"]["one_way_mesh_motion"]
    options = dataclasses.replace(solver_options(cfg), mesh_motion_coupling="segregated")

    def posed(blend):
        return MonolithicFSI(ureter_fluid_scene(cfg, fluid.mesh, fluid.cell_tags, fluid.facet_tags, u_wall, v_wall,
                                                axisymmetric, mesh_motion=blend), options)

    if rule == "extension":
        return posed(None), fluid, MeshMotionChoice(rule, "extension")
    g = UreterGeometry.from_config(cfg)
    has_stent = fluid.mesh.comm.allreduce(fluid.facet_tags.find(tags.FLUID_STENT).size) > 0
    pb = posed(radial_blend(history, g.stent_outer_radius if has_stent else 0.0, g.inner_radius, axisymmetric,
                            g.stent_offset if has_stent else 0.0))
    if rule == "algebraic":
        return pb, fluid, MeshMotionChoice(rule, "algebraic")
    limit = cfg["solver"]["one_way_auto_min_jacobian"]
    t0 = _time.perf_counter()
    choice = MeshMotionChoice(rule, "algebraic", predicted_min_jacobian(pb, history.time, axisymmetric))
    log.info("mesh motion auto: the algebraic map's minimum Jacobian %s (%.1f s)", choice.algebraic.text(),
             _time.perf_counter() - t0)
    if choice.algebraic.value >= limit:
        return pb, fluid, choice
    t0 = _time.perf_counter()
    pb.use_mesh_motion(None)
    choice.used, choice.extension = "extension", predicted_min_jacobian(pb, history.time, axisymmetric)
    log.info("mesh motion auto: the algebraic map's minimum < %g; the extension's %s (%.1f s)", limit,
             choice.extension.text(), _time.perf_counter() - t0)
    if choice.extension.value < limit:
        s = cfg["solver"]
        raise MeshMotionRefused(
            f"both ALE maps fall below solver.one_way_auto_min_jacobian = {limit:g} over the recorded wall motion: "
            f"algebraic {choice.algebraic.text()}; extension ({s['mesh_motion']}, mesh_stiffening "
            f"{s['mesh_stiffening']:g}) {choice.extension.text()}; widen the gap (lower geometry.stricture_fraction), "
            f"move the side holes from under the stricture (hole_pair_spacing, stricture_position) or lower the load "
            f"(peristalsis.peak_traction)")
    return pb, fluid, choice


# ------------------------------------------------------------------------------------------------
# 3. stent
# ------------------------------------------------------------------------------------------------
class QuasiStaticStent:
    """Linear elastic stent under the urine's interface forces, K u = f(t), K factorised once.

    f at the fluid-stent interface nodes is minus the fluid residual at the interface velocity dofs
    (the consistent reaction: the force the urine exerts on the stent, paper eqs. 22-24); the
    interface nodes of the two submeshes coincide (conforming parent mesh, P2 on both sides)."""

    def __init__(self, stent: SubDomain, material, fluid_pb: MonolithicFSI, symmetric_planes: bool,
                 probe_points: np.ndarray):
        if material.kinematics != "linear":
            raise ValueError("the one-way stent is linear elastic (stent.kinematics: linear)")
        msh = stent.mesh
        self.mesh, self.fluid = msh, fluid_pb
        self.ops = ops = Operators(msh, False)
        V = fem.VectorFunctionSpace(msh, ("Lagrange", fluid_pb.options.velocity_degree))
        self.V = V
        self.u = fem.Function(V, name="stent_displacement")
        dx = ufl.Measure("dx", domain=msh, metadata={"quadrature_degree": fluid_pb.options.quadrature_degree})
        a = physics.elastic_residual(ops, material, ufl.TrialFunction(V), ufl.TestFunction(V), dx)
        # fixed end faces (paper eq. 20) and the mirror planes of the half / quarter models
        conditions = [DirichletCondition("displacement", [tags.STENT_ENDS])]
        if symmetric_planes:
            conditions += [DirichletCondition("displacement", [tag], components=[comp])
                           for tag, comp in ((tags.SYMMETRY_X, 0), (tags.SYMMETRY_Y, 1))]
        self.bcs = bcs = [bc for cond in conditions for bc, _, _ in dirichlet_bcs(cond, V, stent.facet_tags)]
        A = fem_petsc.assemble_matrix(fem.form(a), bcs=bcs)
        A.assemble()
        self.ksp = ksp = PETSc.KSP().create(msh.comm)
        ksp.setOperators(A)
        ksp.setType("preonly")
        ksp.getPC().setType("lu")
        # the stent is small: always a direct factorisation, kept for the whole run
        direct = fluid_pb.options.linear_solver
        ksp.getPC().setFactorSolverType("mumps" if direct == "fieldsplit" else direct)
        self.f = self.u.vector.duplicate()
        self._match_interface(stent)
        self.von_mises = CellField(msh, von_mises(physics.elastic_first_piola(ops, material, self.u)), 1)
        self.probe = PointProbe(msh, probe_points)
        self.residual = fem_petsc.create_vector(fluid_pb.residual_form)
        self.wall_time = 0.0

    def _match_interface(self, stent: SubDomain):
        """Pairs (fluid velocity dof, stent displacement dof) of the interface nodes, by coordinates."""
        pb = self.fluid
        fdim = self.mesh.topology.dim - 1
        Vf, vmap = pb.sub("velocity").collapse()
        vmap = np.asarray(vmap).reshape(-1, 3)
        f_nodes = fem.locate_dofs_topological(Vf, fdim, pb.scene.facet_tags.find(tags.FLUID_STENT))
        s_nodes = fem.locate_dofs_topological(self.V, fdim, stent.facet_tags.find(tags.FLUID_STENT))
        xf = Vf.tabulate_dof_coordinates()[f_nodes]
        xs = self.V.tabulate_dof_coordinates()[s_nodes]
        scale = 1e-9 * max(np.abs(xs).max(), 1e-300)
        key = {tuple(np.round(p / scale).astype(np.int64)): n for p, n in zip(xs, s_nodes)}
        pairs = [(fn, key.get(tuple(np.round(p / scale).astype(np.int64)))) for p, fn in zip(xf, f_nodes)]
        missing = sum(1 for _, sn in pairs if sn is None)
        if missing or len(pairs) != len(s_nodes):
            raise RuntimeError(f"fluid-stent interface nodes do not match ({missing} of {len(pairs)} unpaired, "
                               f"{len(s_nodes)} on the stent side)")
        self.fluid_dofs = vmap[[fn for fn, _ in pairs]]                      # (n, 3) dofs of the mixed space
        self.stent_dofs = 3 * np.array([sn for _, sn in pairs])[:, None] + np.arange(3)

    def update(self, pb: MonolithicFSI) -> None:
        """Solve for the stent displacement under the current urine state; refresh the stress."""
        t0 = _time.perf_counter()
        r = self.residual
        pb.assemble_reaction(r)
        f = self.f
        with f.localForm() as loc:
            loc.set(0.0)
        f.array_w[self.stent_dofs.ravel()] = -r.array_r[self.fluid_dofs.ravel()]
        fem_petsc.set_bc(f, self.bcs)
        self.ksp.solve(f, self.u.vector)
        self.u.x.scatter_forward()
        self.von_mises.update()
        self.wall_time += _time.perf_counter() - t0



# ------------------------------------------------------------------------------------------------
# the run
# ------------------------------------------------------------------------------------------------
def write_wall_motion(cfg: dict, out_path: str) -> xr.Dataset:
    """Step 1 of the rung as a job of its own: the wall over [0, time.end] in steps of time.dt, written
    atomically. Every one-way run of the study reads it (their wall is the same: geometry and load do not
    depend on the stent model or the 3D mesh)."""
    ds = wall_history(cfg, cfg["time"]["end"], cfg["time"]["dt"]).to_dataset(cfg)
    write_netcdf(ds, out_path)
    return ds


def pose(cfg: dict, spec: RunSpec, wall_path: str | None, settings: TimeSettings, mesh, cell_tags,
         facet_tags) -> pipeline.Posed:
    """The rung on the run's mesh: the wall motion (read from `wall_path`, or solved), the urine alone on the
    fluid submesh, the quasi-static stent on the stent submesh, the probes and the one-way diagnostics."""
    if wall_path:
        history = WallHistory.from_dataset(open_netcdf(wall_path, WALL_MOTION), cfg, settings.end, settings.dt)
        log.info("wall (r-z) motion read from %s (%d steps, solved in %.1f s)", wall_path, len(history.time) - 1,
                 history.wall_time)
    else:
        history = wall_history(cfg, settings.end, settings.dt)

    axisymmetric = spec.symmetry == "axisymmetric"
    pb, fluid, motion = fluid_problem(cfg, mesh, cell_tags, facet_tags, history, axisymmetric)

    g = UreterGeometry.from_config(cfg)
    model = StentModel.from_config(cfg, spec.model)
    z = np.linspace(0.0, g.length, N_LINE)
    stent = None
    if model.stent and not axisymmetric:
        _, _, stent_material = materials(cfg)
        stent = QuasiStaticStent(extract(mesh, cell_tags, facet_tags, [tags.STENT]), stent_material, pb,
                                 spec.symmetry != "full", g.stent_probe_points(z))
    obs = UreterProbes(pb, cfg, model, spec.symmetry, cfg["time"]["probe_times"], wall=RecordedWall(history, z),
                       stent=stent)
    diag = OneWayDiagnostics(pb, cfg["fluid"]["reference_pressure"], stent)

    def attrs() -> dict:
        extra = {
            # the wall's solve time, in this run or in the shared wall_motion job (wall_motion_file)
            "wall_solve_time_s": round(history.wall_time, 2),
            "wall_motion_file": str(wall_path or ""),
            "one_way_mesh_motion": motion.used,
            "one_way_mesh_motion_rule": motion.rule,
            "one_way_predicted_min_jacobian": motion.algebraic.value,
            "one_way_predicted_min_jacobian_time": motion.algebraic.time,
            "one_way_predicted_extension_min_jacobian": motion.extension.value,
            "one_way_predicted_extension_min_jacobian_time": motion.extension.time,
            "one_way_mesh_motion_boundary_mismatch": pb.mesh_motion_mismatch,
            "one_way_max_wall_pressure_deviation": diag.max_wall_pressure_deviation,
            "one_way_peristaltic_peak_traction": cfg["peristalsis"]["peak_traction"],
        }
        if stent is not None:
            extra.update(one_way_max_stent_displacement=diag.max_stent_displacement,
                         one_way_hole_diameter=g.hole_radius * 2, stent_solve_time_s=round(stent.wall_time, 2))
        return extra

    def summary() -> str:
        return (f" (max |p - p_ref| on the wall {diag.max_wall_pressure_deviation:.1f} Pa vs load "
                f"{cfg['peristalsis']['peak_traction']:.0f} Pa"
                + (f"; max stent displacement {diag.max_stent_displacement:.2e} m vs hole {2 * g.hole_radius:.1e} m"
                   if stent is not None else "") + ")")

    return pipeline.Posed(
        pb, obs, lambda q: oneway_parts(pb, stent, q),
        solver=(f"one-way: r-z wall (Mooney-Rivlin, BDF2) -> urine alone on the fluid submesh (ALE "
                f"P2-P1, {pb.mesh_motion_solver} mesh motion, BDF2, Newton + {pb.options.linear_solver}) -> "
                f"quasi-static linear stent (LU once)"),
        observers=[diag], attrs=attrs, summary=summary,
        description=f" ({fluid.mesh.topology.index_map(fluid.mesh.topology.dim).size_global} fluid)")


def run(cfg: dict, spec: RunSpec, out_path: str, checkpoint_path: str | None = None, wall_path: str | None = None):
    """One-way solve of one model on one mesh (serial); writes the same probe dataset as the fully
    coupled run (ureterfsi.study.coupled.run), with fidelity "one_way" and the one-way diagnostics. wall_path: a
    wall_motion dataset (write_wall_motion) to read instead of solving the wall."""
    if MPI.COMM_WORLD.size > 1:
        raise SystemExit("the one-way rung runs on one process (fidelity one_way); use fully_coupled under MPI")
    return pipeline.run(cfg, spec, out_path, checkpoint_path, "one_way", partial(pose, cfg, spec, wall_path), wall_path)


class OneWayDiagnostics(Observer):
    """What the one-way rung leaves out, measured as it runs: the largest |p - p_ref| of the urine on the
    ureter wall (a load the wall solve does not see) and the largest stent displacement (a motion the
    urine does not see). Registered after UreterProbes, which updates the stent."""

    def __init__(self, pb: MonolithicFSI, reference_pressure: float, stent: QuasiStaticStent | None):
        P, pmap = pb.sub("pressure").collapse()
        fdim = pb.mesh.topology.dim - 1
        self.dofs = np.asarray(pmap)[fem.locate_dofs_topological(
            P, fdim, pb.scene.facet_tags.find(tags.FLUID_URETER))]
        self.pb, self.p_ref, self.stent = pb, reference_pressure, stent
        self.max_wall_pressure_deviation, self.max_stent_displacement = 0.0, 0.0

    def observe(self, problem, step):
        if self.dofs.size:
            dev = float(np.max(np.abs(self.pb.x.x.array[self.dofs] - self.p_ref)))
            self.max_wall_pressure_deviation = max(self.max_wall_pressure_deviation, dev)
        if self.stent is not None:
            u = self.stent.u.x.array.reshape(-1, 3)
            self.max_stent_displacement = max(self.max_stent_displacement, float(np.linalg.norm(u, axis=1).max()))

    def state(self):
        return {"p": self.max_wall_pressure_deviation, "u": self.max_stent_displacement}

    def load_state(self, state):
        self.max_wall_pressure_deviation, self.max_stent_displacement = state["p"], state["u"]
