"""What lies beyond the ureter's open end faces (config `ends`): the renal pelvis at the kidney end (z = 0),
the bladder and the vesicoureteral junction at the bladder end (z = L), as engine open boundaries
(fsi.end_conditions). Pressures are gauge pressures above the paper's reference pressure p_ref.

kidney   open      f0 = p_ref (paper eq. 5)
         pressure  f0 = p_ref + pelvic_pressure
         pelvis    a compliance C filled at the urine production Q_prod: C dp/dt = Q_prod - Q_in, p(0) = p_ref +
                   pelvic_pressure (Compartment; Q_in the whole ureter's inflow)
bladder  open      f0 = p_ref (paper eq. 5)
         pressure  p_b = p_ref + filling_pressure
         voiding   p_b + detrusor_pressure g(t): half-cosine rise over voiding_rise from voiding_start, held for
                   voiding_hold, half-cosine release over voiding_release
         cough     p_b + cough_pressure sin(pi (t - cough_start) / cough_duration) during the cough
junction (bladder not `open`): `valve` a one-way resistance to p_b (Valve), `open` f0 = p_b, `auto` the valve
without a stent and open with one (a stent holds the junction open).
"""
from __future__ import annotations

import ufl

from ureterfsi.config.end_pressures import Arithmetic, bladder_pressure, wall_pressure, wall_pressure_posed
from ureterfsi.mesh import tags
from ureterfsi.mesh.geometry import SYMMETRY_FRACTION, UreterGeometry

from ..fsi import Compartment, OpenBoundary, Valve, Waveform
from ..fsi.probes import inside_radius


UFL = Arithmetic(ufl.cos, ufl.sin, ufl.min_value, ufl.max_value, lambda x: ufl.conditional(ufl.gt(x, 0.0), 1.0, 0.0))


def wall_urine_pressure(cfg: dict):
    """The urine pressure above p_ref the one-way rung's r-z wall takes on its inner surface, p(z, t) of UFL
    expressions (config.end_pressures.wall_pressure), or None with both ends open (the paper's one-way wall)."""
    return wall_pressure(cfg, UFL) if wall_pressure_posed(cfg) else None


def junction_is_valve(ends: dict, has_stent: bool) -> bool:
    """Whether the vesicoureteral junction closes against backflow: `valve`, or `auto` without a stent."""
    rule = ends["bladder"]["junction"]
    return rule == "valve" or (rule == "auto" and not has_stent)


def end_boundaries(cfg: dict, has_stent: bool, symmetry: str) -> list:
    """The open boundaries of the inlet (kidney) and outlet (bladder) faces of a model in `symmetry` (its 0D
    conditions see the whole ureter's flux: flux_scale = 1 / mesh.geometry.SYMMETRY_FRACTION). Both `open`: one
    boundary at p_ref, the paper's."""
    ends, fluid = cfg["ends"], cfg["fluid"]
    p_ref, beta = fluid["reference_pressure"], fluid["backflow_stabilisation"]
    scale = 1.0 / SYMMETRY_FRACTION[symmetry]
    k, b = ends["kidney"], ends["bladder"]
    if k["condition"] == "open" and b["condition"] == "open":
        return [OpenBoundary([tags.INLET, tags.OUTLET], normal_stress=p_ref, backflow=beta)]
    pelvis = p_ref + k["pelvic_pressure"]
    kidney = {"open": OpenBoundary([tags.INLET], p_ref, beta),
              "pressure": OpenBoundary([tags.INLET], pelvis, beta)}.get(k["condition"])
    if kidney is None:
        production = k["urine_production"]
        kidney = OpenBoundary([tags.INLET], pelvis, beta, flux_scale=scale,
                              condition=Compartment(k["pelvis_compliance"], lambda t: production, pelvis))
    if b["condition"] == "open":
        bladder = OpenBoundary([tags.OUTLET], p_ref, beta)
    elif junction_is_valve(ends, has_stent):
        bladder = OpenBoundary([tags.OUTLET], p_ref, beta, flux_scale=scale, condition=Valve(
            bladder_pressure(ends, p_ref), b["junction_forward_resistance"], b["junction_backward_resistance"],
            b["junction_smoothing_pressure"]))
    elif b["condition"] == "pressure":
        bladder = OpenBoundary([tags.OUTLET], p_ref + b["filling_pressure"], beta)
    else:
        bladder = OpenBoundary([tags.OUTLET], p_ref, beta, condition=Waveform(bladder_pressure(ends, p_ref)))
    return [kidney, bladder]


def lumen_indicator(cfg: dict, mesh, has_stent: bool, axisymmetric: bool):
    """The scene's flux_split: the stent lumen on the end faces, inside the stent's mid-wall radius (as the probes'
    lumen fluxes, ureterfsi.study.probes); None without a stent or in r-z (no lumen apart from the annulus there)."""
    if not has_stent or axisymmetric:
        return None
    g = UreterGeometry.from_config(cfg)
    return inside_radius(mesh, g.probe_radius, g.stent_offset)


def symmetry_of(facet_tags_present: set, axisymmetric: bool) -> str:
    """The symmetry of a model mesh from its mirror planes (none: full, one: half, two: quarter)."""
    if axisymmetric:
        return "axisymmetric"
    return ("full", "half", "quarter")[len({tags.SYMMETRY_X, tags.SYMMETRY_Y} & facet_tags_present)]


def default_ends(cfg: dict) -> bool:
    """Both ends open at p_ref (the paper's)."""
    return cfg["ends"]["kidney"]["condition"] == "open" and cfg["ends"]["bladder"]["condition"] == "open"

