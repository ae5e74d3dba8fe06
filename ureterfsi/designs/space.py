"""Design studies (config `design_studies`): a base model's configuration varied over stent, wall and load
parameters, each design point a configuration of its own with its own chain of jobs.

A study is a grid (``full_factorial``: every combination; ``one_at_a_time``: the base point and each value of
one parameter with the others at the base) or a sample (``sobol`` or ``latin_hypercube`` of
``scipy.stats.qmc``, or ``saltelli``: SALib's Saltelli design of N (2 D + 2) rows for Sobol' indices; seeded,
scaled to the bounds). A point is named by a stable id, the first 10 hex digits
of the SHA-256 of its parameter values; its configuration is the base configuration with the point's
overrides (``PARAMETERS``), validated like any configuration (``ureterfsi.config.checks.check_config``: the
schema, then the checks), so an impossible design is refused before any job starts, in one line naming the
parameter.

What a point recomputes follows from content-addressed identities: the mesh (``mesh_id``: geometry, mesh
sizes, model row, level, symmetry) and, on the one-way rung, the r-z wall motion (``wall_id``:
``ureterfsi.config.wall_sections``). A stent or hole change gives a new mesh and urine solve on the shared
wall motion; a wall or load change gives one wall motion per distinct wall, shared by every stent on it; a
stricture (the obstruction, ``geometry.stricture_*``) changes both the wall and the mesh.

A point's mesh symmetry follows from its parameters (``UreterGeometry.symmetry``): the quarter model while both
mirror planes hold (aligned or rotated hole pairs), the half model y >= 0 for a stent offset along x
(``stent_eccentricity``); a stent-free base model run axisymmetric stays axisymmetric.

Results (``ureterfsi.designs.results.study_dataset``): the scalars of every point (peak and mean outlet flow, backflow volume, flow
through each side hole, the share of the outlet flow exchanged through the holes, the share of the outlet flow
inside the stent lumen, peak stent von Mises stress, peak wall displacement, the pressure drop p_in - p_out between
the end faces: its peak |.| and its mean) and the time series behind them, on one dimension per parameter for a full
factorial grid, else on a ``design`` dimension with the parameters as coordinates; per point the one-way mesh motion
it used (a study's ``one_way_mesh_motion: auto`` chooses per point, ureterfsi.study.oneway.fluid_problem). A
Saltelli design adds the point of each sample row (``saltelli_point``: rows repeat, e.g. B_A1 = A_B2 for D = 2, and
each point runs once) and the first-order and total Sobol' indices of each quantity with their confidence intervals
(``design_results.sobol_indices``, SALib.analyze.sobol).

Trust at every point (``ureterfsi.designs.rung_check``): a study on a rung cheaper than fully coupled is checked at the corners
of its design space (``expand_rung_check``: each corner a Point on the 10 mm segment, solved on the study's rung and
fully coupled; ``design_results.rung_check_dataset``: the rung error per corner and quantity), and its dataset says per point
whether it lies in the checked region with every corner within the tolerance.

SALib and scipy.stats (~1 s to import) are imported where a sample is drawn or analysed: configuration validation
imports this module.
"""
from __future__ import annotations

import copy
import hashlib
import json
import math
from dataclasses import dataclass, field


from ureterfsi.mesh.geometry import UreterGeometry
from ureterfsi.data.cf import DESIGN_PARAMETERS, cf_meta
from ureterfsi.designs import rung_check as rc

FRENCH = 1.0e-3 / 3.0                  # m, 1 Fr = 1/3 mm
FRENCH_RANGE = (4.8, 8.0)              # Fr, the clinical range of ureteral stent sizes
ID_DIGITS = 10
VALUE_DIGITS = 10                      # significant digits a parameter value keeps (ids and configs agree)
RESERVED_NAMES = ("meshes", "wall_motion")   # directories of results/designs/


@dataclass(frozen=True)
class Parameter:
    name: str
    part: str                          # "stent": re-mesh + urine solve; "wall": wall motion + urine solve;
                                       # "solve": the solve alone (the stent material)

    @property
    def units(self) -> str:
        return cf_meta(self.name, DESIGN_PARAMETERS)[0]

    @property
    def long_name(self) -> str:
        return cf_meta(self.name, DESIGN_PARAMETERS)[1]


# the parameters (units and long_name: ureterfsi.data.cf.DESIGN_PARAMETERS) and what each re-runs;
# stricture_* (geometry.stricture_*): a new wall motion and a new mesh; hole_pair_rotation
# (geometry.hole_arrangement, 0 = aligned, 90 = rotated_90) and stent_eccentricity (geometry.stent_offset): a new mesh;
# occlusion_position, occlusion_length (geometry.occlusion_*, a complete occlusion; length 0 = none): a new mesh and wall
PARAMETERS = {name: Parameter(name, part) for name, part in (
    ("hole_diameter", "stent"), ("hole_pair_spacing", "stent"), ("stent_outer_diameter", "stent"),
    ("stent_wall_thickness", "stent"), ("stent_youngs_modulus", "solve"), ("wall_stiffness_scale", "wall"),
    ("peak_traction", "wall"), ("pulse_speed", "wall"), ("stricture_fraction", "wall"), ("stricture_length", "wall"),
    ("stricture_position", "wall"), ("hole_pair_rotation", "stent"), ("stent_eccentricity", "stent"),
    ("occlusion_position", "wall"), ("occlusion_length", "wall"))}
ARRANGEMENT = {0.0: "aligned", 90.0: "rotated_90"}     # hole_pair_rotation -> geometry.hole_arrangement
STRICTURE = ("stricture_fraction", "stricture_length", "stricture_position")
MOONEY_RIVLIN = ("c10", "c01", "c20", "c02", "c11")
# config keys each parameter sets (to name the parameter an invalid point's error comes from)
CONFIG_KEYS = {
    "hole_diameter": ("geometry.hole_diameter", "mesh.sizes.hole"),
    "hole_pair_spacing": ("models.", "geometry.hole_end_clearance"),
    "stent_outer_diameter": ("geometry.stent_inner_diameter", "geometry.stent_wall_thickness"),
    "stent_wall_thickness": ("geometry.stent_wall_thickness", "geometry.stent_inner_diameter", "mesh.sizes.stent_wall"),
    "stent_youngs_modulus": ("stent.",),
    "wall_stiffness_scale": ("ureter.",),
    "peak_traction": ("peristalsis.",),
    "pulse_speed": ("peristalsis.",),
    "stricture_fraction": ("geometry.stricture_fraction",),
    "stricture_length": ("geometry.stricture_position", "geometry.stricture_fraction"),
    "stricture_position": ("geometry.stricture_position",),
    "hole_pair_rotation": ("geometry.hole_arrangement",),
    "stent_eccentricity": ("geometry.stent_offset",),
    "occlusion_position": ("geometry.occlusion_position", "geometry.occlusion_length"),
    "occlusion_length": ("geometry.occlusion_length", "geometry.occlusion_position"),
}


@dataclass
class Point:
    id: str
    values: dict                       # parameter -> value (SI units)
    config: dict                       # the point's validated configuration
    mesh_id: str
    wall_id: str | None                # None on the fully coupled rung (no separate wall solve)
    symmetry: str                      # from the point's geometry (point_symmetry)
    model: str = ""                    # the model it solves: the study's, or a reference's own
    rung: str = ""                     # the rung it is solved on: the study's, or fully coupled where escalated
    name: str = ""                     # a reference run's name (design_studies.<study>.references)


@dataclass
class RungCheck:
    """The study's rung checked against the fully coupled model at the corners of its design space
    (ureterfsi.designs.rung_check)."""
    mode: str                          # all | axes (auto resolved)
    tolerance: float
    segment: str                       # the segment overlay's path, as configured
    on_segment: bool                   # the study runs on the segment itself (its corners reuse its points)
    low: dict                          # parameter -> minimum of the design space
    high: dict                         # parameter -> maximum
    centre: dict                       # parameter -> the axes corners' centre
    on_failure: str = "report"         # report | escalate: the points nearest a failing corner solved fully coupled
    corners: list = field(default_factory=list)   # Point per corner (its configuration on the segment)
    reuses: dict = field(default_factory=dict)    # corner id -> the study point whose run is the corner's rung run

    def inside(self, values: dict) -> bool:
        return rc.inside(values, self.mode, self.low, self.high, self.centre)

    def corner(self, corner_id: str) -> "Point":
        for c in self.corners:
            if c.id == corner_id:
                return c
        raise KeyError(f"the rung check has no corner {corner_id}")


@dataclass
class Study:
    name: str
    model: str
    level: str
    rung: str
    kind: str                          # full_factorial | one_at_a_time | sobol | latin_hypercube | saltelli
    parameters: list                   # names, in configuration order
    base: dict                         # parameter -> value of the base configuration
    grid: dict = field(default_factory=dict)   # full factorial: parameter -> values (the dataset's dimensions)
    points: list = field(default_factory=list)
    rows: list = field(default_factory=list)   # saltelli: the point id of each sample row, in SALib's order
    check: "RungCheck | None" = None           # the rung check at the corners (None: not checked)
    references: list = field(default_factory=list)   # Point per reference run (design_studies.<study>.references)
    field_points: list = field(default_factory=list)  # ids of the points whose field figures are drawn (field_figures)

    def point(self, point_id: str) -> Point:
        """A design point or a reference run by its id."""
        for p in self.points + self.references:
            if p.id == point_id:
                return p
        raise KeyError(f"design study {self.name} has no point {point_id}")


def _short_hash(data) -> str:
    text = json.dumps(data, sort_keys=True, separators=(",", ":"), default=str)
    return hashlib.sha256(text.encode()).hexdigest()[:ID_DIGITS]


def _round(v: float) -> float:
    return float(f"{float(v):.{VALUE_DIGITS}g}")


def point_id(values: dict) -> str:
    """Stable id of a design point: hash of its parameter values (rounded to VALUE_DIGITS digits)."""
    return _short_hash({k: f"{_round(v):.{VALUE_DIGITS}g}" for k, v in values.items()})


def run_rung(cfg: dict, model: str) -> tuple[str, str]:
    """(fidelity, symmetry) of a model's runs: study.runs overrides of study.fidelity and mesh.symmetry."""
    over = cfg["study"]["runs"].get(str(model), {})
    return over.get("fidelity", cfg["study"]["fidelity"]), over.get("symmetry", cfg["mesh"]["symmetry"])


def base_values(cfg: dict, model: str) -> dict:
    """Every parameter's value in the base configuration (model `model`)."""
    g, m = cfg["geometry"], cfg["models"][model]
    return {"hole_diameter": g["hole_diameter"], "hole_pair_spacing": m["hole_pair_spacing"],
            "stent_outer_diameter": g["stent_inner_diameter"] + 2 * g["stent_wall_thickness"],
            "stent_wall_thickness": g["stent_wall_thickness"],
            "stent_youngs_modulus": cfg["stent"]["youngs_modulus"], "wall_stiffness_scale": 1.0,
            "peak_traction": cfg["peristalsis"]["peak_traction"], "pulse_speed": cfg["peristalsis"]["speed"],
            "hole_pair_rotation": {v: k for k, v in ARRANGEMENT.items()}[g["hole_arrangement"]],
            "stent_eccentricity": g["stent_offset"], "occlusion_position": g["occlusion_position"],
            "occlusion_length": g["occlusion_length"]} | {
        p: g[p] for p in STRICTURE}


def apply(cfg: dict, model: str, values: dict) -> dict:
    """The base configuration with a point's overrides (without `design_studies`, unvalidated).

    The stent keeps its outer diameter when its wall thickness changes (inner = outer - 2 t); a pair spacing s
    gives floor(L/s) + 1 pairs at clip(k s, c, L - c) (Table 1 rule, ureterfsi.mesh.geometry.hole_pair_positions);
    the wall stiffness scale multiplies c10, c01, c20, c02, c11 (kappa fixed, as the calibration does)."""
    out = copy.deepcopy({k: v for k, v in cfg.items() if k != "design_studies"})
    g, base = out["geometry"], base_values(cfg, model)
    if "hole_diameter" in values:
        g["hole_diameter"] = values["hole_diameter"]
    if "stent_outer_diameter" in values or "stent_wall_thickness" in values:
        outer = values.get("stent_outer_diameter", base["stent_outer_diameter"])
        t = values.get("stent_wall_thickness", base["stent_wall_thickness"])
        g["stent_wall_thickness"], g["stent_inner_diameter"] = t, _round(outer - 2 * t)
    if "hole_pair_spacing" in values:
        s = values["hole_pair_spacing"]
        out["models"][model].update(hole_pair_spacing=s, holes=2 * (math.floor(g["length"] / s + 1e-9) + 1),
                                    label=f"{s * 1e3:g} mm")
    if "stent_youngs_modulus" in values:
        out["stent"]["youngs_modulus"] = values["stent_youngs_modulus"]
    if "wall_stiffness_scale" in values:
        for c in MOONEY_RIVLIN:
            out["ureter"][c] = _round(cfg["ureter"][c] * values["wall_stiffness_scale"])
    if "peak_traction" in values:
        out["peristalsis"]["peak_traction"] = values["peak_traction"]
    if "pulse_speed" in values:
        out["peristalsis"]["speed"] = values["pulse_speed"]
    g.update({p: values[p] for p in STRICTURE if p in values})
    if "hole_pair_rotation" in values:
        g["hole_arrangement"] = ARRANGEMENT[values["hole_pair_rotation"]]
    if "stent_eccentricity" in values:
        g["stent_offset"] = values["stent_eccentricity"]
    g.update({p: values[p] for p in ("occlusion_position", "occlusion_length") if p in values})
    return out


def point_symmetry(cfg: dict, base_symmetry: str) -> str:
    """A design point's mesh symmetry: axisymmetric if its base model runs so (no stent), else the smallest model
    its mirror planes allow (ureterfsi.mesh.geometry.UreterGeometry.symmetry)."""
    return base_symmetry if base_symmetry == "axisymmetric" else UreterGeometry.from_config(cfg).symmetry


def map_parameters(grid: dict) -> list:
    """The parameters of a full-factorial grid {parameter: values} that a map can span (two or more values)."""
    return [p for p, v in grid.items() if len(v) >= 2]
