"""The cases of the stability matrix as data: each axis of the configuration's `stability.axes` names what
its value sets (docs/stability.md lists the axes and their units)."""
from __future__ import annotations

import math
from copy import deepcopy
from dataclasses import dataclass

from ..config import checks   # the module, not its names: importing it runs this package (checks uses .naming)
from ..config.reading import deep_merge
from ..config.schema import schema_defaults
from ureterfsi.data.cf import cf_meta
from .naming import Case

SYMMETRY = "axisymmetric"
SCENES = {"rz": "r-z (axisymmetric), fully coupled monolithic ALE, P2-P2-P1-P0, BDF2",
          "holes": "3D, one-way: r-z wall -> urine alone on the fluid submesh (ALE P2-P1, segregated mesh "
                   "motion, BDF2), stent rigid"}


@dataclass(frozen=True)
class Axis:
    """A varied quantity. Its value sets `sets`: a config path ("peristalsis.speed"), the run's "dt" or
    "level", or "hole_elements" (the 3D hole scene, hole_sizes); a ratio axis multiplies the value by the
    sum of the config values at `per`. `parameter` is its variable in the dataset, `label` and `scale`
    (log, or symlog for a list that includes 0) those of its stability-map axis."""
    sets: str
    parameter: str
    label: str
    scale: str = "log"
    per: tuple = ()
    same_distance: bool = False    # the run's end scales by baseline / value: the pulse travels as far

    @property
    def units(self) -> str:
        return cf_meta(self.parameter)[0]


AXIS = {
    "time_step": Axis("dt", "time_step", "time step"),
    "mesh_level": Axis("level", "cells", "r-z mesh level"),
    "bulk_ratio": Axis("ureter.bulk_modulus", "bulk_ratio", "near-incompressibility kappa / (C10 + C01) of the wall",
                       per=("ureter.c10", "ureter.c01")),
    "density_ratio": Axis("ureter.density", "density_ratio", "density ratio wall / urine", per=("fluid.density",)),
    "load_amplitude": Axis("peristalsis.peak_traction", "peak_traction", "peak traction of the peristaltic pulse",
                           "symlog"),
    "wave_speed": Axis("peristalsis.speed", "wave_speed", "speed of the peristaltic pulse", same_distance=True),
    "wave_width": Axis("peristalsis.width", "wave_width", "width of the peristaltic pulse"),
    "viscosity": Axis("fluid.dynamic_viscosity", "dynamic_viscosity", "dynamic viscosity of the urine"),
    "hole_elements": Axis("hole_elements", "hole_elements_measured", "elements across a side hole (3D, one-way)"),
}
# axis -> (units, long name, scale of the stability-map axis); parameter variable of the dataset per axis
AXES = {k: (a.units, a.label, a.scale) for k, a in AXIS.items()}
AXIS_PARAMETER = {k: a.parameter for k, a in AXIS.items()}


def settings(cfg: dict) -> dict:
    """The `stability` section of cfg with the schema's defaults filled in (no section: the baseline alone)."""
    return deep_merge({"axes": {}} | schema_defaults("stability"), cfg.get("stability") or {})


def cases(cfg: dict) -> list[Case]:
    """Every case of the matrix: the baseline first, then each axis's values in config order."""
    out = [Case("baseline")]
    for axis, values in settings(cfg)["axes"].items():
        out += [Case(axis, v if axis == "mesh_level" else float(v)) for v in values]
    return out


def case_by_name(cfg: dict, name: str) -> Case:
    for c in cases(cfg):
        if c.name == name:
            return c
    raise KeyError(f"no stability case {name!r}; cases: {[c.name for c in cases(cfg)]}")


def _get(cfg: dict, path: str):
    for key in path.split("."):
        cfg = cfg[key]
    return cfg


def _set(cfg: dict, path: str, value) -> None:
    *parents, key = path.split(".")
    for k in parents:
        cfg = cfg[k]
    cfg[key] = value


def hole_sizes(c: dict, level: str, n: float) -> None:
    """Mesh sizes of n elements across a side-hole diameter at `level`, in the case's config c.

    The stent-wall size caps the hole size (the minimum of the size fields): a hole coarser than it coarsens
    the stent wall too. The resolution minima follow, below the study's on purpose, so that the case stays
    consistent with its mesh (ureterfsi.config.check_resolution)."""
    f_level = float(c["mesh"]["levels"][level]["size_factor"])
    sizes, g, minima = c["mesh"]["sizes"], c["geometry"], c["mesh"]["resolution_minima"]
    sizes["hole"] = g["hole_diameter"] / (n * f_level)
    sizes["stent_wall"] = max(sizes["stent_wall"], sizes["hole"])
    minima["hole"] = min(minima["hole"], n)
    minima["stent_wall"] = min(minima["stent_wall"], g["stent_wall_thickness"] / (sizes["stent_wall"] * f_level))


def case_setup(cfg: dict, case: Case) -> dict:
    """Configuration of one case: {"cfg": modified copy, "dt", "level", "end", "model", "scene", "symmetry",
    "parameters": {...}}. A `stability` section that ureterfsi.config.check_stability refuses raises its
    ConfigError; an unknown axis a ValueError."""
    st = settings(cfg)
    c = deepcopy(cfg)
    run = {"dt": float(cfg["time"]["dt"]), "level": str(st["level"]), "end": float(st["end"])}
    scene, model, symmetry, hole_elements = "rz", str(st["model"]), SYMMETRY, math.nan
    if case.axis in AXIS:
        axis = AXIS[case.axis]
        value = str(case.value) if axis.sets == "level" else float(case.value)
        if axis.same_distance:
            run["end"] *= _get(cfg, axis.sets) / value
        if axis.sets in run:
            run[axis.sets] = value
        elif axis.sets == "hole_elements":
            scene, model, symmetry = "holes", str(st["holes"]["model"]), str(st["holes"]["symmetry"])
            hole_elements = value
            if run["level"] in cfg["mesh"]["levels"]:
                hole_sizes(c, run["level"], value)
        else:
            _set(c, axis.sets, value * (sum(_get(cfg, p) for p in axis.per) if axis.per else 1.0))
    elif case.axis != "baseline":
        raise ValueError(f"unknown stability axis {case.axis!r}; one of baseline, {', '.join(AXES)}")
    checks.check_stability(cfg)
    u, f, p = c["ureter"], c["fluid"], c["peristalsis"]
    level = run["level"]
    params = {"time_step": run["dt"], "mesh_level": level, "bulk_ratio": u["bulk_modulus"] / (u["c10"] + u["c01"]),
              "density_ratio": u["density"] / f["density"], "peak_traction": p["peak_traction"],
              "wave_speed": p["speed"], "wave_width": p["width"], "dynamic_viscosity": f["dynamic_viscosity"],
              "hole_elements": hole_elements, "end_time": run["end"]}
    # the baseline of each scene: the r-z baseline case, and the hole case on the study's own mesh
    default_elements = (cfg["geometry"]["hole_diameter"]
                        / (cfg["mesh"]["sizes"]["hole"] * cfg["mesh"]["levels"][level]["size_factor"]))
    params["is_baseline"] = int(case.axis == "baseline" or (
        scene == "holes" and abs(hole_elements - default_elements) <= 1e-6 * default_elements))
    return {"cfg": c, "dt": run["dt"], "level": level, "end": run["end"], "model": model, "scene": scene,
            "symmetry": symmetry, "parameters": params}
