"""The stented-ureter scene (paper §2): tagged mesh + study configuration -> engine Scene.

Regions: urine (Newtonian, ALE), ureter wall (Mooney-Rivlin, mixed u-p), stent (Hooke or SVK).
Loads: travelling Gaussian outward traction on the ureter outer surface (paper §2.4.2, eq. 21).
Boundaries: open inlet/outlet at the reference pressure (eq. 5) or the configured end conditions (scenes.ends),
fixed ureter and stent end faces (eq. 20), mesh fixed on the open faces, mirror planes of the half/quarter models, axis of the
axisymmetric model.
"""
from __future__ import annotations

import math

import ufl

from ureterfsi.mesh import tags

from ..fsi import (DirichletCondition, FluidRegion, LinearElastic, MooneyRivlin, NewtonianFluid,
                   Scene, SolidRegion, SurfaceLoad)
from .ends import end_boundaries, lumen_indicator, symmetry_of

FWHM_PER_SIGMA = 2.0 * math.sqrt(2.0 * math.log(2.0))


def pulse_sigma(peristalsis: dict) -> float:
    """Standard deviation (m) of the Gaussian pulse from the configured width and its measure."""
    w = peristalsis["width"]
    return w / FWHM_PER_SIGMA if peristalsis["width_measure"] == "fwhm" else w


def pulse_centre(peristalsis: dict, t: float) -> float:
    """Axial position (m) of the pulse centre at time t: z_c = z_0 + c t."""
    return peristalsis["start_position"] + peristalsis["speed"] * t


def ramp(t, ramp_time):
    """Half-cosine rise 0 -> 1 over ramp_time (UFL or float t)."""
    if ramp_time <= 0.0:
        return 1.0
    if isinstance(t, (int, float)):
        return 0.5 * (1.0 - math.cos(math.pi * t / ramp_time)) if t < ramp_time else 1.0
    return ufl.conditional(ufl.lt(t, ramp_time), 0.5 * (1.0 - ufl.cos(math.pi * t / ramp_time)), 1.0)


def peristaltic_pressure(peristalsis: dict, z, t):
    """Magnitude (Pa) of the peristaltic traction: A ramp(t) exp(-(z - z_c(t))^2 / (2 sigma^2))."""
    sigma = pulse_sigma(peristalsis)
    zc = peristalsis["start_position"] + peristalsis["speed"] * t
    exp = ufl.exp if not isinstance(z, (int, float)) else math.exp
    return (peristalsis["peak_traction"] * ramp(t, peristalsis["ramp_time"])
            * exp(-((z - zc) ** 2) / (2.0 * sigma**2)))


def load_direction(peristalsis: dict, N, axial_component: int):
    """The dead load's direction: the reference outward normal N (eq. 21; peristalsis.along "normal"), or its radial
    part N - (N . e_z) e_z ("radial"), which leaves the flanks of a narrowed wall without an axial push; the two
    agree on a straight tube."""
    sign = 1.0 if peristalsis["direction"] == "outward" else -1.0
    if peristalsis["along"] == "normal":
        return sign * N
    return sign * ufl.as_vector([0.0 if i == axial_component else N[i] for i in range(N.ufl_shape[0])])


def peristaltic_traction(peristalsis: dict, axial_component: int):
    """SurfaceLoad callable: dead load P d(N) (eq. 21: P N = F_A N) with d the load_direction."""

    def traction(X, t, N):
        return peristaltic_pressure(peristalsis, X[axial_component], t) * load_direction(peristalsis, N,
                                                                                          axial_component)

    return traction


def materials(cfg: dict):
    f, u, s = cfg["fluid"], cfg["ureter"], cfg["stent"]
    urine = NewtonianFluid(f["density"], f["dynamic_viscosity"])
    wall = MooneyRivlin(u["c10"], u["c01"], u["c20"], u["c02"], u["c11"], u["bulk_modulus"], u["density"])
    stent = LinearElastic(s["youngs_modulus"], s["poisson_ratio"], s["density"], s["kinematics"])
    return urine, wall, stent


def ureter_scene(cfg: dict, mesh, cell_tags, facet_tags, axisymmetric: bool = False,
                 peristalsis: dict | None = None) -> Scene:
    """Scene of one stent model on a tagged mesh (full, half, quarter or axisymmetric).

    `peristalsis` overrides cfg["peristalsis"] (e.g. a different amplitude in a stability study).
    """
    urine, wall, stent = materials(cfg)
    present = set(int(v) for v in cell_tags.values)
    present = set(mesh.comm.allreduce(sorted(present)))  # tags held by any rank
    has_stent = tags.STENT in present
    load = peristalsis or cfg["peristalsis"]
    axial = 1 if axisymmetric else 2

    solids = [SolidRegion([tags.URETER], wall)]
    fixed = [tags.URETER_ENDS]
    if has_stent:
        solids.append(SolidRegion([tags.STENT], stent))
        fixed.append(tags.STENT_ENDS)

    dirichlet = [DirichletCondition("velocity", fixed),
                 DirichletCondition("displacement", fixed + [tags.INLET, tags.OUTLET])]
    facet_present = set(mesh.comm.allreduce(sorted(set(int(v) for v in facet_tags.values))))
    mirror = [(tags.AXIS, 0)] if axisymmetric else [(tags.SYMMETRY_X, 0), (tags.SYMMETRY_Y, 1)]
    for tag, comp in mirror:
        if tag in facet_present:
            dirichlet += [DirichletCondition("velocity", [tag], components=[comp]),
                          DirichletCondition("displacement", [tag], components=[comp])]

    return Scene(
        mesh, cell_tags, facet_tags,
        fluid=FluidRegion([tags.FLUID], urine),
        solids=solids,
        open_boundaries=end_boundaries(cfg, has_stent, symmetry_of(facet_present, axisymmetric)),
        loads=[SurfaceLoad([tags.URETER_OUTER], peristaltic_traction(load, axial))],
        dirichlet=dirichlet,
        axisymmetric=axisymmetric,
        name="ureter",
        flux_split=lumen_indicator(cfg, mesh, has_stent, axisymmetric),
    )


def ureter_fluid_scene(cfg: dict, mesh, cell_tags, facet_tags, wall_displacement, wall_velocity,
                       axisymmetric: bool = False, mesh_motion=None) -> Scene:
    """The urine alone on the fluid part of a model's mesh (one-way rung, ureterfsi.study.oneway): the inner
    ureter wall moves as prescribed (callables of (x, t)), the stent surfaces are held still, open
    inlet/outlet at the reference pressure (eq. 5) or the configured end conditions (scenes.ends), mesh fixed on the
    open faces, mirror planes / axis;
    mesh_motion: the ALE map over the whole urine domain (x, t), or None for the engine's extension."""
    urine, _, _ = materials(cfg)
    dirichlet = [DirichletCondition("velocity", [tags.FLUID_URETER], wall_velocity),
                 DirichletCondition("displacement", [tags.FLUID_URETER], wall_displacement)]
    facet_present = set(mesh.comm.allreduce(sorted(set(int(v) for v in facet_tags.values))))
    if tags.FLUID_STENT in facet_present:
        dirichlet += [DirichletCondition("velocity", [tags.FLUID_STENT]),
                      DirichletCondition("displacement", [tags.FLUID_STENT])]
    dirichlet.append(DirichletCondition("displacement", [tags.INLET, tags.OUTLET]))
    mirror = [(tags.AXIS, 0)] if axisymmetric else [(tags.SYMMETRY_X, 0), (tags.SYMMETRY_Y, 1)]
    for tag, comp in mirror:
        if tag in facet_present:
            dirichlet += [DirichletCondition("velocity", [tag], components=[comp]),
                          DirichletCondition("displacement", [tag], components=[comp])]
    return Scene(mesh, cell_tags, facet_tags, fluid=FluidRegion([tags.FLUID], urine),
                 open_boundaries=end_boundaries(cfg, tags.FLUID_STENT in facet_present,
                                                symmetry_of(facet_present, axisymmetric)),
                 dirichlet=dirichlet, axisymmetric=axisymmetric, name="ureter-urine", mesh_motion=mesh_motion,
                 flux_split=lumen_indicator(cfg, mesh, tags.FLUID_STENT in facet_present, axisymmetric))
