"""Plausible ranges of the configuration's magnitudes (SI units), each with its reason.

A value outside its range is refused by ``ureterfsi.config`` (``check_plausible``). Most such values are a
unit slip (mm written as m, kPa as Pa, cP as Pa s, ms as s): the message then names the unit that fits.
The ranges are wide (a decade or more around the physiology) so that they catch slips, not choices.
"""
from __future__ import annotations

import re
from dataclasses import dataclass


@dataclass(frozen=True)
class Range:
    """Closed interval [low, high] in `units`, with the one-line reason for it."""
    low: float
    high: float
    units: str
    reason: str


_DT = Range(1e-6, 10.0, "s", "a time step of 1 us to 10 s (the paper: 10 ms)")
_END = Range(1e-4, 600.0, "s", "up to 10 min of simulated time; a peristaltic cycle is 2-10 s (the paper: 3 s)")
_WIDTH = Range(1e-3, 0.5, "m", "a peristaltic bolus is 1-5 cm long (the paper: 1 cm)")
_SPEED = Range(1e-4, 1.0, "m/s", "peristaltic waves travel 2-6 cm/s (the paper: 2 cm/s)")
_VISCOSITY = Range(1e-4, 0.1, "Pa s", "urine is 0.7-1.3 mPa s (1 cP = 1e-3 Pa s)")
_TRACTION = Range(1e2, 1e7, "Pa", "ureteral contractions exert kPa, the paper 50 kPa; 10 MPa tears any soft tissue")
_MOONEY_RIVLIN = Range(-1e8, 1e8, "Pa", "soft-tissue hyperelastic constants are kPa to MPa")

# dotted key ("*" stands for any one key, "[*]" for any list index) -> plausible range
RANGES: dict[str, Range] = {
    "geometry.length": Range(5e-3, 0.5, "m", "a ureter segment, 5 mm up to the whole ~0.3 m ureter"),
    "geometry.ureter_outer_diameter": Range(1e-3, 3e-2, "m", "human ureters are 3-10 mm across, ~25 mm dilated"),
    "geometry.ureter_wall_thickness": Range(1e-4, 5e-3, "m", "the ureter wall is 0.5-2 mm thick"),
    "geometry.stent_inner_diameter": Range(1e-4, 5e-3, "m", "ureteral stents (3-8 Fr) have 0.3-2 mm lumens"),
    "geometry.stent_wall_thickness": Range(2e-5, 5e-3, "m", "stent walls are 0.1-0.5 mm thick"),
    "geometry.hole_diameter": Range(5e-5, 3e-3, "m", "stent side holes are 0.3-1 mm across"),
    "geometry.hole_end_clearance": Range(1e-5, 0.25, "m", "between a hole radius and half the longest segment"),
    "models.*.hole_pair_spacing": Range(0.0, 0.5, "m", "0 (no stent) up to the longest segment"),
    "fluid.density": Range(500.0, 2000.0, "kg/m^3", "urine is 1000-1035 kg/m^3"),
    "fluid.dynamic_viscosity": _VISCOSITY,
    "fluid.reference_pressure": Range(-1e4, 1e5, "Pa", "urinary-tract pressures are 0-15 kPa (gauge)"),
    "ends.kidney.pelvic_pressure": Range(0.0, 4000.0, "Pa", "normal pelvic pressure is 0 to a few cmH2O, "
                                         "obstructed up to ~40 cmH2O (4 kPa)"),
    "ends.kidney.urine_production": Range(1e-10, 1e-7, "m^3/s", "a kidney makes 0.5-2 mL/min (1e-8-3e-8 m^3/s)"),
    "ends.kidney.pelvis_compliance": Range(1e-11, 1e-7, "m^3/Pa", "a pelvis of a few mL: 0.01-10 mL/cmH2O"),
    "ends.bladder.filling_pressure": Range(0.0, 5000.0, "Pa", "bladder filling pressure is 5-15 cmH2O (0.5-1.5 kPa)"),
    "ends.bladder.detrusor_pressure": Range(0.0, 15000.0, "Pa", "voiding detrusor pressure is 40-70 cmH2O, "
                                            "obstructed up to ~150 cmH2O (15 kPa)"),
    "ends.bladder.cough_pressure": Range(0.0, 25000.0, "Pa", "cough vesical pressure peaks 50-150 cmH2O (15 kPa)"),
    "ends.bladder.voiding_*": Range(0.0, 3600.0, "s", "a void lasts seconds to a minute"),
    "ends.bladder.cough_*": Range(0.0, 3600.0, "s", "a cough lasts tenths of a second"),
    "ends.bladder.junction_*_resistance": Range(1e3, 1e16, "Pa s/m^3", "1 mm-wide channels are ~1e7-1e8 Pa s/m^3"),
    "ends.bladder.junction_smoothing_pressure": Range(1e-3, 100.0, "Pa", "well below a cmH2O (98 Pa)"),
    "ends.one_way_pressure_tolerance": Range(0.0, 1.0, "1", "a fraction of the peristaltic load"),
    "ureter.c10": _MOONEY_RIVLIN,
    "ureter.c01": _MOONEY_RIVLIN,
    "ureter.c20": _MOONEY_RIVLIN,
    "ureter.c02": _MOONEY_RIVLIN,
    "ureter.c11": _MOONEY_RIVLIN,
    "ureter.bulk_modulus": Range(1e4, 1e12, "Pa", "water is 2.2 GPa; 1 TPa exceeds any solid"),
    "ureter.density": Range(500.0, 2000.0, "kg/m^3", "soft tissue is 1000-1100 kg/m^3"),
    "ureter.design_wall_displacement": Range(1e-5, 1e-2, "m", "the paper's design rule: about 1 mm"),
    "stent.youngs_modulus": Range(1e5, 3e11, "Pa", "silicone 1-10 MPa, polyurethane to 100 MPa, metal to 200 GPa"),
    "stent.density": Range(500.0, 1e4, "kg/m^3", "polymer stents 1000-1300, metal stents up to 8000 kg/m^3"),
    "peristalsis.peak_traction": _TRACTION,
    "peristalsis.width": _WIDTH,
    "peristalsis.speed": _SPEED,
    "peristalsis.ramp_time": Range(0.0, 60.0, "s", "a load ramp of at most a minute (the paper's cycle: seconds)"),
    "time.end": _END,
    "time.dt": _DT,
    "mesh.sizes.*": Range(1e-6, 1e-2, "m", "elements of 1 um to 1 cm in a ureter 10 mm across"),
    "mesh.levels.*.size_factor": Range(0.05, 20.0, "1", "a size factor of 0.05 has 8000x the elements of 1"),
    "solver.newton_rtol": Range(1e-14, 1e-2, "1", "below 1e-14 is round-off; above 1e-2 is not converged"),
    "solver.newton_atol": Range(1e-16, 1e-2, "1", "below 1e-16 is round-off; above 1e-2 is not converged"),
    "solver.newton_max_iterations": Range(1, 200, "1", "Newton converges in a few iterations or not at all"),
    "solver.max_step_halvings": Range(0, 20, "1", "20 halvings are a step of 1e-6 dt"),
    "ladder.end": _END,
    "ladder.rungs.*.dt": _DT,
    "stability.end": _END,
    "stability.max_wall_time": Range(1.0, 1e6, "s", "1 s to 11 days of wall-clock time per case"),
    "stability.axes.time_step[*]": _DT,
    "stability.axes.wave_speed[*]": _SPEED,
    "stability.axes.wave_width[*]": _WIDTH,
    "stability.axes.viscosity[*]": _VISCOSITY,
    "stability.axes.load_amplitude[*]": Range(0.0, _TRACTION.high, "Pa", "0 (no load) " + _TRACTION.reason),
    "stability.axes.hole_elements[*]": Range(1.0, 100.0, "1", "100 elements across a hole is a 5 um element"),
    "scenes.*.tolerance": Range(0.0, 1.0, "1", "a relative error above 100 % tolerates anything"),
}

# Mooney-Rivlin small-strain shear modulus 2(c10 + c01)
SHEAR_MODULUS = Range(1e3, 1e8, "Pa", "soft tissue: 1 kPa (fat) to 100 MPa (tendon); ureter wall ~0.1-1 MPa")

# unit slips worth naming: SI value = written value * factor
_SLIPS = {
    "m": ((1e-3, "mm"), (1e-2, "cm")),
    "Pa": ((1e3, "kPa"), (1e6, "MPa")),
    "Pa s": ((1e-3, "mPa s (cP)"),),
    "s": ((1e-3, "ms"),),
    "kg/m^3": ((1e3, "g/cm^3"),),
    "m/s": ((1e-2, "cm/s"), (1e-3, "mm/s")),
}


def _regex(pattern: str) -> re.Pattern:
    text = re.escape(pattern).replace(r"\[\*\]", r"\[[0-9]+\]").replace(r"\*", r"[^.\[\]]+")
    return re.compile(text)


_COMPILED = [(_regex(p), r) for p, r in RANGES.items()]


def range_of(key: str) -> Range | None:
    """The plausible range of a dotted key (``models.2.hole_pair_spacing``, ``time.probe_times[0]``)."""
    return next((r for rx, r in _COMPILED if rx.fullmatch(key)), None)


def unit_slip(value: float, rng: Range) -> str:
    """The unit the value was probably written in, as a hint ('in mm? 0.01 m'), or ''."""
    for factor, name in _SLIPS.get(rng.units, ()):
        if rng.low <= value * factor <= rng.high:
            return f"in {name}? that is {value * factor:g} {rng.units}"
    return ""
