"""The configured end pressures (config `ends`) as plain functions of time, without the engine: the bladder
pressure waveform (ureterfsi.scenes.ends poses it) and the urine pressure the one-way rung's wall assumes
(ureterfsi.scenes.wall_rz loads the wall with it; ureterfsi.study.oneway.rung compares it with the urine's). Each
function takes the arithmetic it is evaluated in (`FLOATS`, or the UFL operations of the scene that poses it)."""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable


@dataclass(frozen=True)
class Arithmetic:
    """cos, sin, the smaller and the larger of two values, 1 where a value is > 0 else 0: of floats (FLOATS) or of
    UFL expressions."""
    cos: Callable
    sin: Callable
    min: Callable
    max: Callable
    positive: Callable


FLOATS = Arithmetic(math.cos, math.sin, min, max, lambda x: 1.0 if x > 0 else 0.0)


def half_cosine(s, m: Arithmetic = FLOATS):
    """0 -> 1 over s in [0, 1], smooth."""
    return 0.5 * (1.0 - m.cos(math.pi * m.min(m.max(s, 0.0), 1.0)))


def bladder_pressure(ends: dict, p_ref: float, m: Arithmetic = FLOATS):
    """The bladder pressure p_b(t) (Pa, absolute in the model's reference) of the configured condition."""
    b = ends["bladder"]
    base = p_ref + b["filling_pressure"]
    if b["condition"] == "voiding":
        t0, rise, hold, release = (b[k] for k in ("voiding_start", "voiding_rise", "voiding_hold", "voiding_release"))

        def voiding(t):
            up = half_cosine((t - t0) / rise, m)
            down = half_cosine((t - t0 - rise - hold) / release, m)
            return base + b["detrusor_pressure"] * (up - down)
        return voiding
    if b["condition"] == "cough":
        t0, dur = b["cough_start"], b["cough_duration"]

        def cough(t):   # sin(pi s) on 0 < s < 1, zero outside
            s = (t - t0) / dur
            return base + b["cough_pressure"] * m.sin(math.pi * s) * m.positive(s) * m.positive(1.0 - s)
        return cough
    return lambda t: base


def wall_pressure_posed(cfg: dict) -> bool:
    """Whether the one-way rung's wall takes an end pressure (an end not `open`); with both ends open it is the
    paper's one-way wall, loaded by the peristalsis alone."""
    return cfg["ends"]["kidney"]["condition"] != "open" or cfg["ends"]["bladder"]["condition"] != "open"


def wall_pressure(cfg: dict, m: Arithmetic = FLOATS):
    """The mean urine pressure above p_ref (Pa) the one-way rung's wall assumes on its inner surface, p_a(z, t):
    linear in z between the kidney end p_k(t) and the bladder end p_b(t) - p_ref, each as configured (`open`: 0;
    kidney `pressure`: pelvic_pressure; a pelvis at its steady drainage pressure, the bladder's: the segment's and
    an open junction's resistance times the production left out). choice: a priori, so one wall motion serves every
    model and no second urine solve is needed; a junction closed against the bladder (a stent-free valve under
    voiding), a pelvis lagging the bladder and the peristaltic pressure are what the urine solve finds otherwise,
    measured against p_a (OneWayDiagnostics) and refused beyond ends.one_way_pressure_tolerance."""
    ends, p_ref, length = cfg["ends"], cfg["fluid"]["reference_pressure"], cfg["geometry"]["length"]
    kidney = ends["kidney"]["condition"]
    if ends["bladder"]["condition"] == "open":
        bladder = lambda t: 0.0    # noqa: E731
    else:
        p_b = bladder_pressure(ends, p_ref, m)
        bladder = lambda t: p_b(t) - p_ref    # noqa: E731
    pelvis = ends["kidney"]["pelvic_pressure"]
    p_k = {"open": lambda t: 0.0, "pressure": lambda t: pelvis, "pelvis": bladder}[kidney]

    def p(z, t):
        s = z / length
        return (1.0 - s) * p_k(t) + s * bladder(t)
    return p
