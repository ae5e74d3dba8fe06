"""The configured end pressures (config `ends`) as plain functions of time, without the engine: the bladder
pressure waveform (ureterfsi.scenes.ends poses it) and the one-way rung's refusal of end pressures its wall ignores
(checked with the configuration)."""
from __future__ import annotations

import math


def half_cosine(s: float) -> float:
    """0 -> 1 over s in [0, 1], smooth."""
    s = min(max(s, 0.0), 1.0)
    return 0.5 * (1.0 - math.cos(math.pi * s))


def bladder_pressure(ends: dict, p_ref: float):
    """The bladder pressure p_b(t) (Pa, absolute in the model's reference) of the configured condition."""
    b = ends["bladder"]
    base = p_ref + b["filling_pressure"]
    if b["condition"] == "voiding":
        t0, rise, hold, release = (b[k] for k in ("voiding_start", "voiding_rise", "voiding_hold", "voiding_release"))

        def voiding(t):
            up = half_cosine((t - t0) / rise)
            down = half_cosine((t - t0 - rise - hold) / release)
            return base + b["detrusor_pressure"] * (up - down)
        return voiding
    if b["condition"] == "cough":
        t0, dur = b["cough_start"], b["cough_duration"]

        def cough(t):
            s = (t - t0) / dur
            return base + (b["cough_pressure"] * math.sin(math.pi * s) if 0.0 < s < 1.0 else 0.0)
        return cough
    return lambda t: base


def max_end_pressure(cfg: dict) -> tuple[float, str]:
    """(largest end pressure above p_ref over [0, time.end] as configured, its key): the pelvic pressure of a kidney
    that is not open (a pelvis's initial pressure), the bladder pressure sampled over the run."""
    ends, p_ref = cfg["ends"], cfg["fluid"]["reference_pressure"]
    found = [(0.0, "")]
    if ends["kidney"]["condition"] != "open":
        found.append((abs(ends["kidney"]["pelvic_pressure"]), "ends.kidney.pelvic_pressure"))
    if ends["bladder"]["condition"] != "open":
        p_b = bladder_pressure(ends, p_ref)
        times = [cfg["time"]["end"] * k / 2000 for k in range(2001)]
        found.append((max(abs(p_b(t) - p_ref) for t in times), f"ends.bladder ({ends['bladder']['condition']})"))
    return max(found)


def one_way_refusal(cfg: dict) -> str:
    """Why the one-way rung (whose wall sees the peristaltic load alone, not the urine pressure) cannot pose the
    configured ends, '' if it can: an end pressure above ends.one_way_max_pressure_fraction of the peak traction."""
    p, key = max_end_pressure(cfg)
    limit = cfg["ends"]["one_way_max_pressure_fraction"] * cfg["peristalsis"]["peak_traction"]
    if p <= limit:
        return ""
    return (f"{key}: an end pressure of {p:.4g} Pa above p_ref exceeds ends.one_way_max_pressure_fraction x "
            f"peristalsis.peak_traction = {limit:.4g} Pa: the one-way rung's wall ignores the urine pressure; use "
            f"fidelity fully_coupled")
