"""The whole-passage quantities of a design study (ureterfsi.designs.results): where the urine passes an obstruction
(a complete occlusion or a stricture) - the stent lumen's share of the flow through the plane of the obstruction's
centre, and which side holes lie upstream (proximal, kidney side) of it; the rung that solved each point (the
study's, or fully coupled where the rung check escalated it); and the study's reference runs (the unstented and the
stented unobstructed segment under the same ends) on a dimension of their own.

The lumen share is measured at the obstruction's centre, not at the outlet: the question is which path the urine
takes past the obstruction, and the outlet's lumen flux is what remains in the stent after the holes downstream have
let urine out into the annulus (and in again). The run files record the flux through that plane and its part inside
the stent (obstruction_flux, obstruction_lumen_flux: ureterfsi.fsi.probes.cut_flux_forms, consistent with the
continuity rows, so a complete occlusion's annulus carries none of it to the solver's tolerance).
"""
from __future__ import annotations

import numpy as np

from ureterfsi.designs import rung_check as rc
from ureterfsi.designs.space import Study
from ureterfsi.mesh.geometry import UreterGeometry

OBSTRUCTION_SERIES = ("obstruction_flux", "obstruction_lumen_flux")
# the reference runs' scalars in a design dataset (reference_<name>, ureterfsi.data.cf.reference_metadata)
REFERENCE_SCALARS = ("peak_outlet_flux", "mean_outlet_flux", "backflow_volume", "stent_lumen_fraction",
                     "peak_wall_displacement", "peak_pressure_drop", "peak_pelvic_pressure", "reflux_volume_lumen",
                     "reflux_volume_annulus", "wall_time")


def trapezoid(y: np.ndarray, t: np.ndarray) -> float:
    """int y dt over the recorded times (trapezoidal rule)."""
    return float(np.sum(0.5 * (y[1:] + y[:-1]) * np.diff(t)))


def lumen_share(q: np.ndarray, lumen: np.ndarray, t: np.ndarray) -> float:
    """integral |Q_lumen| dt / (integral |Q_lumen| dt + integral |Q - Q_lumen| dt) of a flux Q and its part inside
    the stent, over the times t; NaN without flow."""
    inside, outside = trapezoid(np.abs(lumen), t), trapezoid(np.abs(q - lumen), t)
    return inside / (inside + outside) if inside + outside > 0 else np.nan


def obstruction_lumen_fraction(run) -> float:
    """lumen_share through the plane of the obstruction's centre (the run's obstruction_flux, obstruction_lumen_flux);
    NaN without them or without flow."""
    if "obstruction_flux" not in run:
        return np.nan
    q, lumen = (run[k].values.astype(float) for k in OBSTRUCTION_SERIES)
    return lumen_share(q, lumen, run["time"].values.astype(float))


def obstruction_variables(points: list, hole_z: np.ndarray) -> tuple[dict, dict]:
    """(variables, coordinates) on design (and hole): each point's obstruction kind and centre, and per hole
    hole_proximal: 1 upstream of the centre, 0 downstream, NaN without an obstruction (or a missing hole)."""
    geoms = [UreterGeometry.from_config(p.config) for p in points]
    centre = np.array([np.nan if g.obstruction_centre is None else g.obstruction_centre for g in geoms])
    proximal = np.where(np.isfinite(hole_z) & np.isfinite(centre)[:, None], (hole_z < centre[:, None]) * 1.0, np.nan)
    return ({"obstruction": (("design",), np.array([g.obstruction for g in geoms], dtype=object)),
             "obstruction_position": (("design",), centre)},
            {"hole_proximal": (("design", "hole"), proximal)})


def escalated_points(st: Study, corner_ok) -> list:
    """The ids of the study's points solved fully coupled (rung_check.on_failure: escalate), given per corner (in
    the check's order) whether it is within the tolerance: those whose nearest corner failed
    (ureterfsi.designs.rung_check.escalated); none under on_failure: report."""
    ch = st.check
    if ch is None or ch.on_failure != "escalate":
        return []
    failing = [not bool(ok) for ok in np.asarray(corner_ok).ravel()]
    flags = rc.escalated([p.values for p in st.points], [c.values for c in ch.corners], failing, ch.low, ch.high)
    return [p.id for p, f in zip(st.points, flags) if f]


def rung_variable(st: Study, escalated: list) -> dict:
    """The rung that solved each point: the study's, fully coupled where escalated."""
    return {"rung": (("design",), np.array([rc.REFERENCE_RUNG if p.id in escalated else st.rung for p in st.points],
                                            dtype=object))}


def reference_variables(st: Study, scalars: dict) -> tuple[dict, dict]:
    """(variables, coordinates) of the study's reference runs on the reference dimension: reference_<q> for each of
    REFERENCE_SCALARS, from `scalars` {reference id: point_scalars of its run}; empty without references."""
    if not st.references:
        return {}, {}
    data = {f"reference_{q}": (("reference",), np.array([float(scalars[r.id][q]) for r in st.references]))
            for q in REFERENCE_SCALARS}
    return data, {"reference": ("reference", np.array([r.name for r in st.references], dtype=object)),
                  "reference_model": ("reference", np.array([int(r.model) for r in st.references], dtype=np.int32))}


def escalated_from_file(st: Study, path) -> list:
    """escalated_points of a study from its rung check's file (rule design_rung_check)."""
    from ureterfsi.data.checked import Contract, open_netcdf

    with open_netcdf(path, Contract("rung check", variables=("corner_within_tolerance",))) as ds:
        return escalated_points(st, ds["corner_within_tolerance"].values)
