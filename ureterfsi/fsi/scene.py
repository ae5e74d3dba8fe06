"""A scene: everything the engine needs to know about one problem, as plain data.

The engine knows nothing about ureters. A scene supplies a tagged mesh, the material of each tagged
region, the open boundaries, the loads (dead surface tractions, follower pressures, body forces) and the
Dirichlet conditions. Time-dependent data are callables of (x, t) (interpolated each step) or of (X, t[, N])
returning UFL (evaluated in the forms).
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable, Optional, Sequence

from .materials import LinearElastic, MooneyRivlin, NewtonianFluid


@dataclass
class FluidRegion:
    tags: Sequence[int]
    material: NewtonianFluid


@dataclass
class SolidRegion:
    tags: Sequence[int]
    material: MooneyRivlin | LinearElastic


@dataclass
class OpenBoundary:
    """Fluid boundary with prescribed normal stress sigma n = -normal_stress n (paper eq. 5),
    with optional directional backflow stabilisation of strength `backflow` (0 disables). `condition`: a
    Waveform, Compartment or Valve (fsi.end_conditions) whose face pressure replaces normal_stress; it sees the
    whole model's flux, flux_scale times the face's (1 / the modelled fraction of a symmetric model)."""
    tags: Sequence[int]
    normal_stress: float = 0.0
    backflow: float = 1.0
    condition: Optional[object] = None
    flux_scale: float = 1.0


@dataclass
class SurfaceLoad:
    """Traction per reference area on tagged facets: P N = traction(X, t, N), a UFL vector
    (X reference coordinates, t a UFL constant time, N reference outward normal; 3-vectors in
    axisymmetric scenes, components (r, theta, z))."""
    tags: Sequence[int]
    traction: Callable


@dataclass
class FollowerPressure:
    """Pressure on the deformed surface of tagged solid facets: the Cauchy traction -p n per current area,
    i.e. P N = -p J F^-T N per reference area (Nanson), so it follows the deformation; p(X, t) a UFL scalar
    (X reference coordinates, t a UFL constant time), p > 0 pushes into the solid."""
    tags: Sequence[int]
    pressure: Callable


@dataclass
class BodyForce:
    """Force per unit reference volume on tagged solid cells: b(X, t), a UFL vector (3-vectors (r, theta, z)
    in axisymmetric scenes). Gravity is b = rho_0 g with rho_0 the reference density: mass conservation
    (rho J = rho_0) makes it the exact weight in any deformation."""
    tags: Sequence[int]
    force: Callable


@dataclass
class DirichletCondition:
    """Prescribed velocity (field 'velocity') or displacement (field 'displacement') on tagged facets.

    value(x, t) -> array (gdim, n) for all components, or (n,) for a single component;
    None means zero. components=None constrains the whole vector, else only the listed components
    (e.g. symmetry planes: the normal component)."""
    field: str
    tags: Sequence[int]
    value: Optional[Callable] = None
    components: Optional[Sequence[int]] = None


@dataclass
class Scene:
    mesh: object
    cell_tags: object
    facet_tags: object
    fluid: Optional[FluidRegion] = None
    solids: list = field(default_factory=list)
    open_boundaries: list = field(default_factory=list)
    loads: list = field(default_factory=list)             # SurfaceLoad (dead tractions)
    pressure_loads: list = field(default_factory=list)    # FollowerPressure
    body_forces: list = field(default_factory=list)       # BodyForce
    dirichlet: list = field(default_factory=list)
    axisymmetric: bool = False
    name: str = "scene"
    # Fluid-alone scenes only (segregated mesh motion): the ALE mesh displacement over the whole fluid region
    # as a callable (x, t) -> (gdim, n), e.g. a closed-form blend of the prescribed boundary motion. None: the
    # engine extends the boundary displacement by solving SolverOptions.mesh_motion. Where the displacement
    # DirichletConditions apply, their values win (the engine measures the disagreement).
    mesh_motion: Optional[Callable] = None
    # A UFL indicator on the open faces (1 in one part of a face, 0 in the other; e.g. a stent's lumen and the annulus
    # around it): fsi.end_conditions.FaceFlux assembles a face's flux in these two parts. None: one part
    flux_split: Optional[object] = None

    def __post_init__(self):
        if self.fluid is None and not self.solids:
            raise ValueError("a scene needs a fluid region, a solid region, or both")
        for name, kind in (("loads", SurfaceLoad), ("pressure_loads", FollowerPressure),
                           ("body_forces", BodyForce)):
            for item in getattr(self, name):
                if not isinstance(item, kind):
                    raise TypeError(f"Scene.{name} holds {kind.__name__} items, got {type(item).__name__}")
        solid_tags = {t for s in self.solids for t in s.tags}
        for bf in self.body_forces:
            if not set(bf.tags) <= solid_tags:
                raise ValueError(f"BodyForce.tags {sorted(set(bf.tags) - solid_tags)} are not solid cell tags "
                                 f"(solids: {sorted(solid_tags)})")
        for bc in self.dirichlet:
            if bc.field not in ("velocity", "displacement"):
                raise ValueError(f"DirichletCondition.field must be 'velocity' or 'displacement', got {bc.field!r}")
        if self.mesh_motion is not None and (self.solids or self.fluid is None):
            raise ValueError("Scene.mesh_motion prescribes the ALE map of a fluid-alone scene; a scene with solids "
                             "moves its fluid mesh with the solid (SolverOptions.mesh_motion)")
