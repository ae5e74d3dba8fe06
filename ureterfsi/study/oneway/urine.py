"""Step 2 of the one-way rung: the urine alone on the fluid part of the mesh with the recorded wall motion prescribed;
the mesh moved by a closed-form radial blend or a segregated extension problem, chosen by the predicted smallest
Jacobian."""
from __future__ import annotations

import dataclasses
import logging
import math
import time as _time
from dataclasses import dataclass

import numpy as np
from dolfinx import fem

from ureterfsi.mesh import tags
from ureterfsi.fsi import SolveFailure
from ureterfsi.fsi.ale_jacobian import ALEJacobian
from ureterfsi.fsi.operators import Operators
from ureterfsi.fsi.problem import MonolithicFSI
from ureterfsi.fsi.submesh import extract
from ureterfsi.mesh.geometry import UreterGeometry
from ureterfsi.scenes.ureter import ureter_fluid_scene
from ureterfsi.study.options import solver_options
from ureterfsi.study.oneway.wall import WallHistory

log = logging.getLogger("ureterfsi.study.oneway")


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
    options = dataclasses.replace(solver_options(cfg), mesh_motion_coupling="segregated",
                                  urine_step=cfg["solver"]["one_way_urine_step"],
                                  newton_field_rtol=cfg["solver"]["one_way_newton_field_rtol"],
                                  reuse_contraction=cfg["solver"]["one_way_reuse_contraction"])

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
