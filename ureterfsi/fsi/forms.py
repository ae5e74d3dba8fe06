"""The monolithic residual's terms (paper eqs. 16-25), by part, with the cell measure given: the whole problem
integrates them over every cell; the partitioned scheme's wall rows over the solid cells and the urine cells that
touch them (fsi.partitioned)."""
from __future__ import annotations

from dataclasses import dataclass

import ufl

from . import physics
from .materials import LinearElastic, MooneyRivlin


@dataclass
class ResidualTerms:
    urine: object       # ALE Navier-Stokes on the fluid cells and its open boundaries (0 without a fluid)
    solids: object      # inertia, kinematics and elasticity on the solid cells (0 without a solid)
    loads: object       # dead and follower surface loads, body forces (0 without any)


def residual_terms(ops, scene, fields: dict, tests: dict, dvdt, dudt, t, dx, ds, convecting=None,
                   normal_stress=lambda ob: ob.normal_stress) -> ResidualTerms:
    """The terms of the residual in `fields` (UFL parts of the state), `tests` (of the test function), the BDF
    rates dv/dt, du/dt, time t, with the cell and facet measures dx, ds (subdomain data: the scene's tags);
    `convecting`: the urine's convecting velocity if not its own (physics.fluid_ale_residual); normal_stress(open
    boundary): its f0 (default its constant; fsi.end_conditions for a lumped condition)."""
    v, u = fields["velocity"], fields["displacement"]
    phi, psi = tests["velocity"], tests["displacement"]
    urine = 0
    if scene.fluid:
        fl, tags = scene.fluid.material, tuple(scene.fluid.tags)
        urine += physics.fluid_ale_residual(ops, fl, v, fields["pressure"], u, dvdt, dudt, phi, tests["pressure"],
                                            dx(tags), convecting)
        for ob in scene.open_boundaries:
            urine += physics.open_boundary_residual(ops, fl, normal_stress(ob), ob.backflow, v, u, dudt, phi,
                                                    ds(tuple(ob.tags)), convecting)
    solids = 0
    for solid in scene.solids:
        mat, dxs = solid.material, dx(tuple(solid.tags))
        solids += physics.solid_inertia_residual(ops, mat.density, dvdt, phi, dxs)
        solids += physics.kinematic_residual(ops, dudt, v, psi, dxs)
        if isinstance(mat, MooneyRivlin):
            solids += physics.mooney_rivlin_residual(ops, mat, u, fields["solid_pressure"], phi,
                                                     tests["solid_pressure"], dxs)
        elif isinstance(mat, LinearElastic):
            solids += physics.elastic_residual(ops, mat, u, phi, dxs)
        else:
            raise TypeError(f"unsupported solid material {type(mat).__name__}")
    X = ufl.SpatialCoordinate(scene.mesh)
    loads = 0
    for load in scene.loads:
        loads += physics.surface_load_residual(ops, load.traction(X, t, ops.normal()), phi, ds(tuple(load.tags)))
    for load in scene.pressure_loads:
        traction = physics.follower_pressure_traction(ops, load.pressure(X, t), u)
        loads += physics.surface_load_residual(ops, traction, phi, ds(tuple(load.tags)))
    for load in scene.body_forces:
        loads += physics.body_force_residual(ops, load.force(X, t), phi, dx(tuple(load.tags)))
    return ResidualTerms(urine, solids, loads)


def kinematic_mass(ops, scene, trial_velocity, psi, dx):
    """-d/dv of the solids' kinematic rows: the mass matrix int v . psi on the solid cells."""
    zero = ufl.zero(trial_velocity.ufl_shape)
    mass = 0
    for solid in scene.solids:
        mass += -physics.kinematic_residual(ops, zero, trial_velocity, psi, dx(tuple(solid.tags)))
    return mass
