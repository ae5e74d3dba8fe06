"""Trust at every design point: a design study's rung checked against the fully coupled model at the
corners of its design space, on the segment its configuration names (the 10 mm segment by default).

A study on a rung cheaper than ``fully_coupled`` (``one_way``: the scenes' rung) is checked at the corners of its
design space: for each corner the study's rung and the fully coupled model (``fully_coupled_scheme:
partitioned``, 3D, the corner's mesh) solve the corner's configuration on the segment (config
``design_studies.<study>.rung_check.segment``, an overlay: by default the 10 mm segment of
``config/segment-10mm.yaml``; ``config/config.yaml``, the study's own segment, where its corners are its points),
each its own job; the dataset records, per corner and per scalar quantity, the relative error

    e = |q_rung - q_fully_coupled| / s_q

with s_q the fully coupled run's own scale of the quantity at the same corner, as the ladder (``ureterfsi.analyses.ladder``)
divides by the max norm of the reference: for the outlet-flow scalars (peak and mean outlet flow) the largest
|outlet flow| over the run, for the backflow volume the volume through the outlet (integral |Q_out| dt) - a peak or
a mean of a flow that barely turns is near 0 in a short window and would make |q_fc| meaningless as a scale (2 steps
on the 10 mm segment: peak outlet flow 0 on one rung, 1e-12 m3/s on the other, "100 %") - and for the other
quantities (shares, peak stress, peak displacement, peak pressure drop) |q_fully_coupled| itself (``ureterfsi.designs.results.error_scales``; NaN
where the scale is 0 and the values differ, 0 where they agree).

Corners (``corners``): ``all`` - every combination of each varied parameter's minimum and maximum (2^D); ``axes``
- each varied parameter at its minimum and its maximum with the others at the centre (the base value clipped to
the parameter's range), 2 D corners; ``auto`` - ``all`` up to ``ALL_CORNERS_UP_TO`` varied parameters (8
corners), ``axes`` above (2^D fully coupled solves outgrow the study: 16 at D = 4, 32 at D = 5); ``none`` - no
check. A parameter with a single value is not varied and takes it at every corner. The checked region is the
convex hull of the corners: the box for ``all``; for ``axes`` the points with sum_j d_j <= 1, d_j the distance of
x_j from the centre in units of the distance from the centre to the corner on that side. A design point inside
the region whose every corner is within the tolerance is trusted; the dataset and the figure caption name the
others.

Pure functions here (no solver, no ``ureterfsi.designs.space``, no ``ureterfsi.designs.results``): the corner values, the
region test, the segment's configuration and the errors. ``ureterfsi.designs.space`` expands a study's corners,
``ureterfsi.designs.results`` writes the dataset variables.
"""
from __future__ import annotations

import copy
import itertools
import math
from pathlib import Path

import numpy as np

from ureterfsi.config.errors import ConfigError
from ureterfsi.config.reading import deep_merge, read_yaml
from ureterfsi import REPO_ROOT

CORNER_MODES = ("auto", "all", "axes", "none")
ALL_CORNERS_UP_TO = 3                  # varied parameters below which (inclusive) auto takes every corner
DEFAULTS = {"corners": "auto", "tolerance": 0.05, "segment": "config/segment-10mm.yaml", "on_failure": "report"}
ON_FAILURE = ("report", "escalate")
REFERENCE_RUNG = "fully_coupled"
REFERENCE_SCHEME = "partitioned"       # solver.fully_coupled_scheme of the reference solves (3D: docs/performance.md)
# sections of the segment overlay a corner takes: the geometry (its length), the load's start and ramp, the time
# window and the figures' instants (which must be its probe times); not its models (each keeps its spacing, its
# hole count follows the segment's length) nor its study section (but its convergence_time, inside its window)
SEGMENT_SECTIONS = ("geometry", "peristalsis", "time", "figures")


def check_spec(spec: dict | None, rung: str) -> dict:
    """The study's rung_check with its defaults; corners 'none' on the fully coupled rung (nothing to check)."""
    out = DEFAULTS | (spec or {})
    if rung == REFERENCE_RUNG and not spec:
        out["corners"] = "none"
    return out


def ranges(values: list[dict], names: list) -> tuple[dict, dict]:
    """({parameter: minimum}, {parameter: maximum}) over the points' values."""
    return ({p: min(v[p] for v in values) for p in names}, {p: max(v[p] for v in values) for p in names})


def corner_mode(mode: str, lo: dict, hi: dict) -> str:
    """The corner set `auto` resolves to (all up to ALL_CORNERS_UP_TO varied parameters, else axes)."""
    if mode != "auto":
        return mode
    return "all" if sum(lo[p] < hi[p] for p in lo) <= ALL_CORNERS_UP_TO else "axes"


def centre(lo: dict, hi: dict, base: dict) -> dict:
    """The centre of the axes corners: each parameter's base value clipped to its range."""
    return {p: min(max(base[p], lo[p]), hi[p]) for p in lo}


def corner_values(mode: str, lo: dict, hi: dict, base: dict) -> list[dict]:
    """The corners (mode all or axes, see the module docstring), each once, in a stable order."""
    names = list(lo)
    varied = [p for p in names if lo[p] < hi[p]]
    if mode == "all":
        combos = itertools.product(*((lo[p], hi[p]) if p in varied else (lo[p],) for p in names))
        out = [dict(zip(names, c)) for c in combos]
    elif mode == "axes":
        c = centre(lo, hi, base)
        out = [c | {p: end} for p in varied for end in (lo[p], hi[p])] or [c]
    else:
        raise ValueError(f"corner mode must be all or axes, got {mode!r}")
    unique = []
    for v in out:
        if v not in unique:
            unique.append(v)
    return unique


def region_distance(values: dict, mode: str, lo: dict, hi: dict, base: dict) -> float:
    """How far a point lies in the checked region: <= 1 inside (the corners' convex hull), > 1 outside. all: the
    largest normalised distance from the box's middle (max_j |x_j - m_j| / half-range_j); axes: sum_j d_j."""
    d = []
    c = centre(lo, hi, base) if mode == "axes" else {p: 0.5 * (lo[p] + hi[p]) for p in lo}
    for p, x in values.items():
        end = hi[p] if x > c[p] else lo[p]
        if x == c[p]:
            d.append(0.0)
        elif end == c[p]:
            d.append(math.inf)
        else:
            d.append((x - c[p]) / (end - c[p]))
    if not d:
        return 0.0
    return float(max(d) if mode == "all" else sum(d))


def inside(values: dict, mode: str, lo: dict, hi: dict, base: dict, rtol: float = 1e-9) -> bool:
    """Whether a point lies in the checked region (region_distance <= 1, to round-off)."""
    return region_distance(values, mode, lo, hi, base) <= 1.0 + rtol


def segment_overlay(path: str) -> dict:
    """The segment overlay: `path` as given (absolute or relative to the working directory), else relative to the
    repository (the workflow's --directory need not hold it)."""
    for p in (Path(path), REPO_ROOT / path):
        if p.is_file():
            return read_yaml(p)
    raise ConfigError("rung_check.segment", f"no such overlay file {path!r} (nor under {REPO_ROOT})")


def on_segment(cfg: dict, overlay: dict) -> bool:
    """Whether a configuration already runs on the segment (its geometry.length)."""
    length = overlay.get("geometry", {}).get("length")
    return length is None or math.isclose(float(cfg["geometry"]["length"]), float(length), rel_tol=1e-12)


def segment_config(cfg: dict, overlay: dict) -> dict:
    """`cfg` on the segment: the overlay's SEGMENT_SECTIONS merged on top, each stented model's hole count by the
    Table 1 rule (floor(L/s) + 1 pairs) for the segment's length; `cfg` itself if it already runs on the segment."""
    if on_segment(cfg, overlay):
        return copy.deepcopy(cfg)
    out = deep_merge(cfg, {k: v for k, v in overlay.items() if k in SEGMENT_SECTIONS})
    for m in out["models"].values():
        if m["stent"] and m["hole_pair_spacing"] > 0:
            m["holes"] = 2 * (math.floor(out["geometry"]["length"] / m["hole_pair_spacing"] + 1e-9) + 1)
    conv = overlay.get("study", {}).get("convergence_time")
    if conv is not None:                        # the mesh-convergence instant must lie in the segment's window
        out["study"]["convergence_time"] = conv
    return out


def reference_config(cfg: dict) -> dict:
    """A corner's (or an escalated point's) configuration for its fully coupled solve: the partitioned scheme
    (REFERENCE_SCHEME; it carries the lumped end conditions too, docs/end-conditions.md)."""
    out = copy.deepcopy(cfg)
    out["solver"]["fully_coupled_scheme"] = REFERENCE_SCHEME
    return out


def nearest_corners(values: dict, corners: list[dict], lo: dict, hi: dict) -> list[int]:
    """Indices of the corners nearest a point: Euclidean distance with each varied parameter scaled by its range
    (hi - lo; a parameter with one value does not count); every corner at the smallest distance (to round-off)."""
    varied = [p for p in lo if hi[p] > lo[p]]
    d = np.array([math.sqrt(sum(((values[p] - c[p]) / (hi[p] - lo[p])) ** 2 for p in varied)) for c in corners])
    return [int(i) for i in np.flatnonzero(d <= d.min() + 1e-9)]


def escalated(points: list[dict], corners: list[dict], failing: list[bool], lo: dict, hi: dict) -> list[bool]:
    """Per point, whether it is solved fully coupled under `on_failure: escalate`: its region is the points whose
    nearest corner (nearest_corners) it is, and a point is escalated when any of its nearest corners failed the check
    (beyond the tolerance, or not solved)."""
    return [any(failing[i] for i in nearest_corners(v, corners, lo, hi)) for v in points]


def relative_errors(rung: dict, reference: dict, quantities, scales: dict | None = None) -> np.ndarray:
    """|q_rung - q_ref| / s_q of each quantity, s_q = scales[q] where given, else |q_ref| (NaN where either value is
    NaN, or s_q = 0 while the values differ; 0 where they agree)."""
    out = []
    for q in quantities:
        a, b = float(reference[q]), float(rung[q])
        s = abs(float((scales or {}).get(q, a)))
        if not (np.isfinite(a) and np.isfinite(b)):
            out.append(np.nan)
        elif a == b:
            out.append(0.0)
        else:
            out.append(abs(b - a) / s if s > 0 else np.nan)
    return np.array(out, float)
