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

Results (``study_dataset``): the scalars of every point (peak and mean outlet flow, backflow volume, flow
through each side hole, the share of the outlet flow exchanged through the holes, the share of the outlet flow
inside the stent lumen, peak stent von Mises stress, peak wall displacement, the pressure drop p_in - p_out between
the end faces: its peak |.| and its mean) and the time series behind them, on one dimension per parameter for a full
factorial grid, else on a ``design`` dimension with the parameters as coordinates; per point the one-way mesh motion
it used (a study's ``one_way_mesh_motion: auto`` chooses per point, ureterfsi.study.oneway.fluid_problem). A
Saltelli design adds the point of each sample row (``saltelli_point``: rows repeat, e.g. B_A1 = A_B2 for D = 2, and
each point runs once) and the first-order and total Sobol' indices of each quantity with their confidence intervals
(``sobol_indices``, SALib.analyze.sobol).

Trust at every point (``ureterfsi.rung_check``): a study on a rung cheaper than fully coupled is checked at the corners
of its design space (``expand_rung_check``: each corner a Point on the 10 mm segment, solved on the study's rung and
fully coupled; ``rung_check_dataset``: the rung error per corner and quantity), and its dataset says per point
whether it lies in the checked region with every corner within the tolerance.

SALib and scipy.stats (~1 s to import) are imported where a sample is drawn or analysed: configuration validation
imports this module.
"""
from __future__ import annotations

import copy
import hashlib
import itertools
import json
import math
from dataclasses import dataclass, field

import numpy as np
import xarray as xr

from .checked_io import Contract, open_netcdf
from .config.checks import check_config
from .config.errors import ConfigError, fmt
from .config.runs import wall_sections
from .geometry import SYMMETRY_FRACTION, UreterGeometry
from .metadata import DESIGN_PARAMETERS, VARIABLES, cf_meta, rung_check_metadata
from .provenance import provenance_attrs
from . import rung_check as rc

FRENCH = 1.0e-3 / 3.0                  # m, 1 Fr = 1/3 mm
FRENCH_RANGE = (4.8, 8.0)              # Fr, the ureteral stent sizes of the issue (clinical range)
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


# the parameters (units and long_name: ureterfsi.metadata.DESIGN_PARAMETERS) and what each re-runs;
# stricture_* (geometry.stricture_*): a new wall motion and a new mesh; hole_pair_rotation
# (geometry.hole_arrangement, 0 = aligned, 90 = rotated_90) and stent_eccentricity (geometry.stent_offset): a new mesh
PARAMETERS = {name: Parameter(name, part) for name, part in (
    ("hole_diameter", "stent"), ("hole_pair_spacing", "stent"), ("stent_outer_diameter", "stent"),
    ("stent_wall_thickness", "stent"), ("stent_youngs_modulus", "solve"), ("wall_stiffness_scale", "wall"),
    ("peak_traction", "wall"), ("pulse_speed", "wall"), ("stricture_fraction", "wall"), ("stricture_length", "wall"),
    ("stricture_position", "wall"), ("hole_pair_rotation", "stent"), ("stent_eccentricity", "stent"))}
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
}


@dataclass
class Point:
    id: str
    values: dict                       # parameter -> value (SI units)
    config: dict                       # the point's validated configuration
    mesh_id: str
    wall_id: str | None                # None on the fully coupled rung (no separate wall solve)
    symmetry: str                      # from the point's geometry (point_symmetry)


@dataclass
class RungCheck:
    """The study's rung checked against the fully coupled model at the corners of its design space
    (ureterfsi.rung_check)."""
    mode: str                          # all | axes (auto resolved)
    tolerance: float
    segment: str                       # the segment overlay's path, as configured
    on_segment: bool                   # the study runs on the segment itself (its corners reuse its points)
    low: dict                          # parameter -> minimum of the design space
    high: dict                         # parameter -> maximum
    centre: dict                       # parameter -> the axes corners' centre
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

    def point(self, point_id: str) -> Point:
        for p in self.points:
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
            "stent_eccentricity": g["stent_offset"]} | {p: g[p] for p in STRICTURE}


def apply(cfg: dict, model: str, values: dict) -> dict:
    """The base configuration with a point's overrides (without `design_studies`, unvalidated).

    The stent keeps its outer diameter when its wall thickness changes (inner = outer - 2 t); a pair spacing s
    gives floor(L/s) + 1 pairs at clip(k s, c, L - c) (Table 1 rule, ureterfsi.geometry.hole_pair_positions);
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
    return out


def point_symmetry(cfg: dict, base_symmetry: str) -> str:
    """A design point's mesh symmetry: axisymmetric if its base model runs so (no stent), else the smallest model
    its mirror planes allow (ureterfsi.geometry.UreterGeometry.symmetry)."""
    return base_symmetry if base_symmetry == "axisymmetric" else UreterGeometry.from_config(cfg).symmetry


def mesh_sections(cfg: dict, model: str, level: str, symmetry: str) -> dict:
    """The configuration entering a mesh (rule mesh's rerun trigger) with its level and symmetry."""
    return {"geometry": cfg["geometry"], "mesh": cfg["mesh"], "model": cfg["models"][model],
            "level": level, "symmetry": symmetry}


def solve_sections(cfg: dict, model: str) -> dict:
    """The configuration entering one solve (rule solve's rerun trigger)."""
    keys = ("geometry", "fluid", "ureter", "stent", "peristalsis", "time", "mesh", "solver")
    return {k: cfg[k] for k in keys} | {"model": cfg["models"][model]}


# ------------------------------------------------------------------------------------------ expansion

def saltelli_unit_sample(dim: int, size: int, seed: int) -> np.ndarray:
    """SALib's Saltelli design on the unit cube (scrambled Sobol' sequence, second order): size (2 dim + 2) rows
    in the order SALib.analyze.sobol reads them."""
    from SALib.sample import sobol as salib_sample

    problem = {"num_vars": dim, "names": [f"x{i}" for i in range(dim)], "bounds": [[0.0, 1.0]] * dim}
    return salib_sample.sample(problem, size, calc_second_order=True, scramble=True, seed=seed)


def _unit_sample(method: str, dim: int, size: int, seed: int) -> np.ndarray:
    from scipy.stats import qmc

    if method == "saltelli":
        return saltelli_unit_sample(dim, size, seed)
    sampler = qmc.Sobol(dim, scramble=True, seed=seed) if method == "sobol" else qmc.LatinHypercube(dim, seed=seed)
    return sampler.random(size)


def _parameter_key(name: str, spec: dict, param: str) -> str:
    return (f"design_studies.{name}.grid.parameters.{param}" if "grid" in spec
            else f"design_studies.{name}.sample.bounds.{param}")


def _check_study(cfg: dict, name: str, spec: dict) -> None:
    key = f"design_studies.{name}"
    if name in RESERVED_NAMES:
        raise ConfigError(key, f"the name is reserved for results/designs/{name}/; choose another")
    if spec["model"] not in cfg["models"]:
        raise ConfigError(f"{key}.model", f"must be one of models {sorted(cfg['models'], key=int)}, "
                                          f"got {fmt(spec['model'])}")
    if spec["level"] not in cfg["mesh"]["levels"]:
        raise ConfigError(f"{key}.level", f"must be one of mesh.levels {list(cfg['mesh']['levels'])}, "
                                          f"got {fmt(spec['level'])}")
    if ("grid" in spec) == ("sample" in spec):
        raise ConfigError(key, "needs exactly one of grid (values per parameter) or sample (bounds per parameter)")
    params = spec["grid"]["parameters"] if "grid" in spec else spec["sample"]["bounds"]
    if "sample" in spec and "hole_pair_rotation" in params:
        raise ConfigError(_parameter_key(name, spec, "hole_pair_rotation"),
                          f"takes the values {sorted(ARRANGEMENT)} only; vary it on a grid, not in a sample")
    stented = cfg["models"][spec["model"]]["stent"]
    for p in params:
        if PARAMETERS[p].part in ("stent", "solve") and not stented:
            raise ConfigError(_parameter_key(name, spec, p),
                              f"a stent parameter needs a stented base model; model {spec['model']} has no stent")
    rung, symmetry = spec.get("rung") or run_rung(cfg, spec["model"])[0], run_rung(cfg, spec["model"])[1]
    if rung == "one_way" and symmetry == "axisymmetric":
        raise ConfigError(f"{key}.rung", f"one_way needs a 3D mesh; model {spec['model']} runs {symmetry}")
    if "grid" in spec:
        for p, vals in params.items():
            rounded = [_round(v) for v in vals]
            if len(set(rounded)) != len(rounded):
                raise ConfigError(_parameter_key(name, spec, p), f"values must be distinct, got {fmt(list(vals))}")
    else:
        s = spec["sample"]
        for p, (lo, hi) in params.items():
            if not lo < hi:
                raise ConfigError(_parameter_key(name, spec, p), f"bounds must be [low, high] with low < high, "
                                                                 f"got {fmt([lo, hi])}")
        if s["method"] in ("sobol", "saltelli") and s["size"] & (s["size"] - 1):
            raise ConfigError(f"{key}.sample.size", f"a Sobol' sample keeps its balance only at a power of 2, "
                                                    f"got {s['size']}")
        if s["method"] == "saltelli" and len(params) < 2:
            raise ConfigError(f"{key}.sample.bounds", f"a Saltelli design needs at least 2 parameters for Sobol' "
                                                      f"indices, got {len(params)}")


def _point_values(cfg: dict, spec: dict, base: dict) -> tuple[str, list, dict, list]:
    """(kind, parameters, full-factorial grid, [values per point]) of a study."""
    if "grid" in spec:
        mode, params = spec["grid"]["mode"], spec["grid"]["parameters"]
        names = list(params)
        if mode == "full_factorial":
            grid = {p: [_round(v) for v in params[p]] for p in names}
            return mode, names, grid, [dict(zip(names, combo)) for combo in itertools.product(*grid.values())]
        at_base = {p: _round(base[p]) for p in names}
        points = [at_base]
        for p in names:
            points += [at_base | {p: _round(v)} for v in params[p] if _round(v) != at_base[p]]
        return mode, names, {}, points
    s = spec["sample"]
    names = list(s["bounds"])
    lo, hi = (np.array([s["bounds"][p][i] for p in names]) for i in (0, 1))
    unit = _unit_sample(s["method"], len(names), s["size"], s["seed"])
    return s["method"], names, {}, [{p: _round(v) for p, v in zip(names, lo + u * (hi - lo))} for u in unit]


def _precheck(cfg: dict, model: str, values: dict) -> tuple[str, str] | None:
    """(parameter, constraint) of a point the configuration checks would blame on another key, else None."""
    base = base_values(cfg, model)
    outer = values.get("stent_outer_diameter", base["stent_outer_diameter"])
    t = values.get("stent_wall_thickness", base["stent_wall_thickness"])
    lumen = cfg["geometry"]["ureter_outer_diameter"] - 2 * cfg["geometry"]["ureter_wall_thickness"]
    if "stent_outer_diameter" in values:
        fr = outer / FRENCH
        if not FRENCH_RANGE[0] - 1e-9 <= fr <= FRENCH_RANGE[1] + 1e-9:
            return "stent_outer_diameter", (f"{fmt(outer)} m = {fr:.3g} Fr is outside the ureteral stent sizes "
                                            f"{FRENCH_RANGE[0]:g}-{FRENCH_RANGE[1]:g} Fr (1 Fr = 1/3 mm)")
        if not outer < lumen:
            return "stent_outer_diameter", (f"{fmt(outer)} m must be < the ureter lumen diameter {fmt(lumen)} m "
                                            f"(the stent would touch the wall)")
    if ("stent_outer_diameter" in values or "stent_wall_thickness" in values) and not 2 * t < outer:
        p = "stent_wall_thickness" if "stent_wall_thickness" in values else "stent_outer_diameter"
        return p, f"wall thickness {fmt(t)} m leaves no stent lumen in an outer diameter of {fmt(outer)} m"
    return None


def _blame(values: dict, err: ConfigError) -> str:
    """The parameter of a point an invalid configuration key comes from (first match), else the first one."""
    for p in values:
        if any(err.key.startswith(k) for k in CONFIG_KEYS[p]):
            return p
    return next(iter(values))


def _values_text(values: dict) -> str:
    return ", ".join(f"{p} = {fmt(v)}" + ("" if PARAMETERS[p].units == "1" else f" {PARAMETERS[p].units}")
                     for p, v in values.items())


def expand_study(cfg: dict, name: str) -> Study:
    """The design points of study `name`, each with its validated configuration; ConfigError (one line,
    naming the study's parameter) for a study or a point that cannot be posed."""
    spec = cfg["design_studies"][name]
    _check_study(cfg, name, spec)
    model = spec["model"]
    fidelity, base_symmetry = run_rung(cfg, model)
    rung = spec.get("rung") or fidelity
    base = base_values(cfg, model)
    kind, names, grid, all_values = _point_values(cfg, spec, base)
    study = Study(name, model, spec["level"], rung, kind, names, {p: base[p] for p in names}, grid)
    seen = set()
    for values in all_values:
        pid = point_id(values)
        if kind == "saltelli":
            study.rows.append(pid)
        if pid in seen:
            continue
        seen.add(pid)
        bad = _precheck(cfg, model, values)
        if bad:
            raise ConfigError(_parameter_key(name, spec, bad[0]), f"point {pid} ({_values_text(values)}): {bad[1]}")
        pcfg = apply(cfg, model, values)
        pcfg["solver"]["one_way_mesh_motion"] = spec.get("one_way_mesh_motion", pcfg["solver"]["one_way_mesh_motion"])
        try:
            check_config(pcfg)
        except ConfigError as err:
            raise ConfigError(_parameter_key(name, spec, _blame(values, err)),
                              f"point {pid} ({_values_text(values)}) cannot be posed: {err.key}: {err.constraint}") from None
        symmetry = point_symmetry(pcfg, base_symmetry)
        study.points.append(Point(pid, values, pcfg, _short_hash(mesh_sections(pcfg, model, spec["level"], symmetry)),
                                  _short_hash(wall_sections(pcfg)) if rung == "one_way" else None, symmetry))
    study.check = expand_rung_check(cfg, name, spec, study)
    return study


def _space(spec: dict, names: list, all_values: list) -> tuple[dict, dict]:
    """(low, high) of the study's design space: a sample's bounds, else the points' extremes."""
    if "sample" in spec:
        b = spec["sample"]["bounds"]
        return {p: _round(b[p][0]) for p in names}, {p: _round(b[p][1]) for p in names}
    return rc.ranges(all_values, names)


def expand_rung_check(cfg: dict, name: str, spec: dict, study: Study) -> RungCheck | None:
    """The corners of study `name` (ureterfsi.rung_check), each a Point on the segment with its configuration,
    mesh and wall; None if the study is not checked. A corner on a study that runs on the segment is one of its
    points when the grid holds it (`reuses`: its rung run is the point's). ConfigError (one line) for a corner that
    cannot be posed on the segment."""
    key = f"design_studies.{name}.rung_check"
    opts = rc.check_spec(spec.get("rung_check"), study.rung)
    if opts["corners"] == "none":
        return None
    if study.rung == rc.REFERENCE_RUNG:
        raise ConfigError(f"{key}.corners", f"the study's rung is {rc.REFERENCE_RUNG} already: nothing to check; "
                                            f"set none")
    low, high = _space(spec, study.parameters, [p.values for p in study.points])
    mode = rc.corner_mode(opts["corners"], low, high)
    try:
        overlay = rc.segment_overlay(opts["segment"])
    except ConfigError as err:
        raise ConfigError(f"{key}.segment", err.constraint) from None
    seg = rc.segment_config(cfg, overlay)
    check = RungCheck(mode, float(opts["tolerance"]), opts["segment"], rc.on_segment(cfg, overlay), low, high,
                      rc.centre(low, high, study.base))
    base_symmetry = run_rung(cfg, study.model)[1]
    for values in rc.corner_values(mode, low, high, study.base):
        values = {p: _round(v) for p, v in values.items()}
        cid = point_id(values)
        ccfg = apply(seg, study.model, values)
        ccfg["solver"]["one_way_mesh_motion"] = spec.get("one_way_mesh_motion", ccfg["solver"]["one_way_mesh_motion"])
        try:
            check_config(ccfg)
        except ConfigError as err:
            raise ConfigError(key, f"corner {cid} ({_values_text(values)}) cannot be posed on the segment "
                                   f"{opts['segment']}: {err.key}: {err.constraint}") from None
        symmetry = point_symmetry(ccfg, base_symmetry)
        if symmetry == "axisymmetric":
            raise ConfigError(key, f"the fully coupled reference of corner {cid} needs a 3D mesh; model "
                                   f"{study.model} runs axisymmetric")
        corner = Point(cid, values, ccfg, _short_hash(mesh_sections(ccfg, study.model, study.level, symmetry)),
                       _short_hash(wall_sections(ccfg)) if study.rung == "one_way" else None, symmetry)
        check.corners.append(corner)
        same = next((p for p in study.points if p.id == cid), None)
        if same is not None and (same.mesh_id, same.symmetry) == (corner.mesh_id, corner.symmetry) and \
                solve_sections(same.config, study.model) == solve_sections(ccfg, study.model):
            check.reuses[cid] = same.id
    return check


def point_run_path(study: str, point: str) -> str:
    """The run file of a design point (rule design_solve)."""
    return f"results/designs/{study}/{point}/run.nc"


def corner_run_path(study: str, corner: str, rung: str) -> str:
    """The run file of a corner's solve on `rung` (rule design_corner_solve)."""
    return f"results/designs/{study}/rung_check/{corner}/{rung}.nc"


def corner_run_paths(st: Study) -> dict:
    """{corner id: (run file on the study's rung, fully coupled run file)} of a checked study; the rung's run of
    a corner that is one of the study's points (on its segment) is that point's."""
    if st.check is None:
        return {}
    return {c.id: (point_run_path(st.name, st.check.reuses[c.id]) if c.id in st.check.reuses
                   else corner_run_path(st.name, c.id, st.rung), corner_run_path(st.name, c.id, rc.REFERENCE_RUNG))
            for c in st.check.corners}


def corner_solve_request(st: Study, corner_id: str, rung: str) -> tuple[Point, dict]:
    """(corner, configuration) of a corner's solve on `rung`: the study's rung or the fully coupled reference."""
    if st.check is None or rung not in (st.rung, rc.REFERENCE_RUNG):
        raise KeyError(f"design study {st.name} checks no corner {corner_id} on {rung}")
    c = st.check.corner(corner_id)
    return c, rc.reference_config(c.config) if rung == rc.REFERENCE_RUNG else c.config


_CACHE: dict = {}


def studies(cfg: dict) -> dict:
    """{name: Study} of every design study of the configuration (expanded once per configuration)."""
    specs = cfg.get("design_studies") or {}
    key = _short_hash({k: v for k, v in cfg.items()})
    if key not in _CACHE:
        _CACHE.clear()
        _CACHE[key] = {name: expand_study(cfg, name) for name in specs}
    return _CACHE[key]


def check_design_studies(cfg: dict) -> None:
    """Every study expanded and every point validated (called by ureterfsi.config.validate_config)."""
    studies(cfg)


def _points_and_corners(st: Study) -> list:
    return st.points + (st.check.corners if st.check else [])


def mesh_request(cfg: dict, mesh_id: str) -> tuple[dict, str, str, str]:
    """(configuration, model, level, symmetry) of a design mesh, from the first point (or corner) that uses it."""
    for st in studies(cfg).values():
        for p in _points_and_corners(st):
            if p.mesh_id == mesh_id:
                return p.config, st.model, st.level, p.symmetry
    raise KeyError(f"no design point uses mesh {mesh_id}")


def wall_config(cfg: dict, wall_id: str) -> dict:
    """Configuration of a design wall motion, from the first point (or corner) that uses it."""
    for st in studies(cfg).values():
        for p in _points_and_corners(st):
            if p.wall_id == wall_id:
                return p.config
    raise KeyError(f"no design point uses wall motion {wall_id}")


# ------------------------------------------------------------------------------------------ dataset
SCALARS = ("peak_outlet_flux", "mean_outlet_flux", "backflow_volume", "peak_hole_flux", "hole_exchange_volume",
           "hole_exchange_fraction", "stent_lumen_fraction", "peak_stent_von_mises", "peak_wall_displacement",
           "wall_time", "peak_pressure_drop", "mean_pressure_drop")
QUANTITIES = ("peak_outlet_flux", "mean_outlet_flux", "backflow_volume", "hole_exchange_fraction",   # figures, indices
              "stent_lumen_fraction", "peak_stent_von_mises", "peak_wall_displacement", "peak_pressure_drop")
SOBOL_INDICES = {"sobol_first_order": "S1", "sobol_first_order_conf": "S1_conf",   # dataset name: SALib's key
                 "sobol_total": "ST", "sobol_total_conf": "ST_conf"}
SERIES = ("outlet_flux", "inlet_flux", "outlet_lumen_flux", "stent_max_von_mises", "max_wall_displacement",
          "pressure_drop")


def _trapz(y: np.ndarray, t: np.ndarray) -> float:
    return float(np.sum(0.5 * (y[1:] + y[:-1]) * np.diff(t)))


def hole_mirror_weights(run) -> np.ndarray:
    """Per recorded hole, the holes of the full model it stands for: 2 where its opposite hole (same z and axis,
    other side) lies outside the symmetric model (its mirror image, the same flow), else 1."""
    if "hole_flux" not in run:
        return np.zeros(0)
    z, side = run["hole_z"].values, run["hole_side"].values
    axis = run["hole_axis"].values if "hole_axis" in run else np.ones_like(side)
    recorded = {(round(float(a), 9), int(b), float(c)) for a, b, c in zip(z, axis, side)}
    return np.array([1.0 if (round(float(a), 9), int(b), -float(c)) in recorded else 2.0
                     for a, b, c in zip(z, axis, side)])


def pressure_drop(run) -> np.ndarray:
    """p_in - p_out of a run dataset: inlet minus outlet area-mean end-face pressure (Pa; NaN where not recorded)."""
    if "inlet_mean_pressure" not in run:
        return np.full(run.sizes["time"], np.nan)
    return run["inlet_mean_pressure"].values.astype(float) - run["outlet_mean_pressure"].values.astype(float)


def pressure_drop_scalars(run) -> dict:
    """Peak |p_in - p_out| (the pulse drives the urine both ways, so a signed mean partly cancels) and its
    signed time mean (the net drop)."""
    t, dp = run["time"].values.astype(float), pressure_drop(run)
    return {"peak_pressure_drop": float(np.max(np.abs(dp))), "mean_pressure_drop": _trapz(dp, t) / (t[-1] - t[0])}


def point_scalars(run) -> dict:
    """The scalars of one run dataset (ureterfsi.study.probes.probes_dataset); hole flows per hole."""
    t = run["time"].values.astype(float)
    q = run["outlet_flux"].values.astype(float)
    hole = run["hole_flux"].values.astype(float) if "hole_flux" in run else np.zeros((0, t.size))   # (hole, time)
    mirror = hole_mirror_weights(run)
    exchange = np.array([_trapz(np.abs(h), t) for h in hole])
    if "outlet_lumen_flux" in run:
        lumen = run["outlet_lumen_flux"].values.astype(float)
        inside, outside = _trapz(np.abs(lumen), t), _trapz(np.abs(q - lumen), t)
        lumen_fraction = inside / (inside + outside) if inside + outside > 0 else np.nan
    else:
        lumen_fraction = np.nan
    return {"peak_outlet_flux": float(q.max()), "mean_outlet_flux": _trapz(q, t) / (t[-1] - t[0]),
            "backflow_volume": _trapz(np.maximum(-q, 0.0), t),
            "peak_hole_flux": np.abs(hole).max(axis=1) if hole.size else np.zeros(0),
            "hole_exchange_volume": exchange,
            "hole_exchange_fraction": float(np.sum(mirror * exchange)) / _trapz(np.abs(q), t),
            "stent_lumen_fraction": lumen_fraction,
            "peak_stent_von_mises": float(run["stent_max_von_mises"].max()) if "stent_max_von_mises" in run else np.nan,
            "peak_wall_displacement": float(run["max_wall_displacement"].max()),
            "wall_time": float(run.attrs.get("wall_time_s", np.nan))} | pressure_drop_scalars(run)


def mesh_motion_variables(points, runs) -> dict:
    """Per point (on the one-way rung): the ALE map its urine solve used (solver.one_way_mesh_motion, resolved under
    auto), the algebraic map's and the extension's predicted minimum Jacobians (auto, the extension's where the
    algebraic one is below the limit; NaN otherwise) and the run's minimum Jacobian."""
    def attr(p, key, default):
        return runs[p.id].attrs.get(key, default)

    return {"mesh_motion": (("design",), np.array([str(attr(p, "one_way_mesh_motion", "")) for p in points], dtype=object)),
            "predicted_min_jacobian": (("design",), np.array([float(attr(p, "one_way_predicted_min_jacobian", np.nan))
                                                              for p in points])),
            "predicted_extension_min_jacobian": (("design",), np.array(
                [float(attr(p, "one_way_predicted_extension_min_jacobian", np.nan)) for p in points])),
            "min_ale_jacobian": (("design",), np.array([float(runs[p.id]["min_ale_jacobian"].min()) for p in points]))}


# what study_dataset (point_scalars, mesh_motion_variables) relies on in a point's run file (a run file,
# checked_io.RUN_FILE, of which it reads these)
DESIGN_RUN = Contract("run file", variables=("time", "outlet_flux", "max_wall_displacement", "min_ale_jacobian"),
                      units=VARIABLES)
# what the design figures (ureterfsi.plotting_designs, workflow/scripts/design_figures.py) rely on in a study's dataset
DESIGN_DATASET = Contract("design-study dataset", attrs=("study", "design_kind", "model", "points"))
# what study_dataset takes from a study's rung check (rung_check_dataset)
RUNG_CHECK = Contract("rung check", attrs=("rung_check",),
                      variables=("rung_error", "max_rung_error", "rung_tolerance", "corner_within_tolerance"))


def _corner_run(path) -> xr.Dataset:
    """A corner's run file: a run (DESIGN_RUN), or the record of a solve that failed (write_failed_corner)."""
    ds = open_netcdf(path, Contract("corner run file"))
    return ds if "solve_failed" in ds.attrs else open_netcdf(path, DESIGN_RUN)


def rung_check_summary(st: Study, error: np.ndarray, inside: list | None, failed: dict | None = None) -> str:
    """One paragraph on the study's rung check (the dataset's attribute rung_check, the figures' captions): what
    was checked, the largest error against the tolerance, the corners beyond it, those whose solve failed
    (`failed`: corner id -> message) and (unless `inside` is None) the points outside the checked region (or that
    there are none)."""
    ch = st.check
    if ch is None:
        return (f"not checked: the study's rung is {st.rung}" if st.rung == rc.REFERENCE_RUNG else
                f"not checked (design_studies.{st.name}.rung_check.corners: none): the {st.rung} rung's error at "
                f"these designs is not measured")
    where = "the study's own segment" if ch.on_segment else f"the segment {ch.segment}"
    worst = float(np.nanmax(error)) if np.isfinite(error).any() else np.nan
    text = (f"{st.rung} checked against {rc.REFERENCE_RUNG} ({rc.REFERENCE_SCHEME}) at {len(ch.corners)} corners "
            f"({ch.mode}) of the design space on {where}: largest relative error {worst:.2g} "
            f"(tolerance {ch.tolerance:g})")
    failed = failed or {}
    bad = [c.id for c, e in zip(ch.corners, error) if c.id not in failed and not np.nanmax(e, initial=0.0) <= ch.tolerance]
    unmeasured = [c.id for c, e in zip(ch.corners, error) if c.id not in failed and not np.isfinite(e).any()]
    text += (f"; corners beyond the tolerance: {', '.join(bad)}" if bad else
             "; every corner solved within it" if failed else "; every corner within it")
    if unmeasured:
        text += f" (no finite error at {', '.join(unmeasured)})"
    if failed:
        text += "; not checked (a solve failed) at " + "; ".join(f"{k}: {v}" for k, v in failed.items())
    if inside is None:
        return text
    out = [p.id for p, i in zip(st.points, inside) if not i]
    text += (f"; {len(out)} of {len(st.points)} design points outside the checked region: {', '.join(out)}" if out
             else "; every design point inside the checked region")
    return text


def write_failed_corner(cfg: dict, path, rung: str, message: str) -> None:
    """The run file of a corner whose solve on `rung` failed: no data, the failure in its attribute solve_failed
    (rung_check_dataset reports the corner as not checked)."""
    from .metadata import write_netcdf

    ds = xr.Dataset(attrs=provenance_attrs(cfg, rung=rung, solve_failed=message))
    write_netcdf(ds, path, title=f"ureterfsi rung-check corner: the {rung} solve failed")


def error_scales(run) -> dict:
    """The scales of the outlet-flow scalars of a (fully coupled) run for their rung errors (ureterfsi.rung_check):
    max |Q_out| for the peak and the mean outlet flow, integral |Q_out| dt for the backflow volume."""
    t, q = run["time"].values.astype(float), run["outlet_flux"].values.astype(float)
    peak = float(np.max(np.abs(q)))
    return {"peak_outlet_flux": peak, "mean_outlet_flux": peak, "backflow_volume": _trapz(np.abs(q), t)}


def rung_check_dataset(cfg: dict, name: str, corner_paths: dict) -> xr.Dataset:
    """The rung check of study `name` (ureterfsi.rung_check) from its corners' run files {corner id: (run on the
    study's rung, fully coupled run)}: per corner and quantity the relative error, its maximum over the corners,
    the tolerance, per corner whether it is within it and both solves' wall times, the corners' parameter values;
    the attribute rung_check says what was checked and what is outside (rung_check_summary). CF-annotated
    (ureterfsi.metadata.rung_check_metadata)."""
    st = studies(cfg)[name]
    ch = st.check
    if ch is None:
        raise ValueError(f"design study {name} has no rung check (design_studies.{name}.rung_check.corners: none)")
    error, wall = np.full((len(ch.corners), len(QUANTITIES)), np.nan), np.full((len(ch.corners), 2), np.nan)
    failed = {}
    for i, c in enumerate(ch.corners):
        runs = [_corner_run(path) for path in corner_paths[c.id]]
        failed.update({c.id: r.attrs["solve_failed"] for r in runs if "solve_failed" in r.attrs})
        if c.id in failed:
            continue
        rung, ref = (point_scalars(r) for r in runs)
        error[i] = rc.relative_errors(rung, ref, QUANTITIES, error_scales(runs[1]))
        wall[i] = [float(r.attrs.get("wall_time_s", np.nan)) for r in runs]
    corner_ok = np.array([c.id not in failed and np.nanmax(e, initial=0.0) <= ch.tolerance
                          for c, e in zip(ch.corners, error)])
    measured = np.isfinite(error).any(axis=0)
    worst = np.where(measured, np.nanmax(np.where(np.isfinite(error), error, -np.inf), axis=0), np.nan)
    ds = xr.Dataset({"rung_error": (("corner", "quantity"), error),
                     "max_rung_error": (("quantity",), worst),
                     "corner_within_tolerance": (("corner",), corner_ok.astype(np.int8)),
                     "corner_rung_wall_time": (("corner",), wall[:, 0]),
                     "corner_reference_wall_time": (("corner",), wall[:, 1]),
                     "rung_tolerance": ((), ch.tolerance)},
                    coords={"corner": ("corner", [c.id for c in ch.corners]),
                            "quantity": ("quantity", list(QUANTITIES)),
                            **{f"corner_{q}": ("corner", [c.values[q] for c in ch.corners]) for q in st.parameters}})
    meta = rung_check_metadata(st.parameters) | {"quantity": VARIABLES["quantity"]}
    for k in ds.variables:
        ds[k].attrs.update(units=meta[k][0], long_name=meta[k][1])
    attrs = {"rung_check": rung_check_summary(st, error, None, failed), "rung_check_corners": ch.mode,
             "rung_check_tolerance": ch.tolerance, "rung_check_segment": ch.segment,
             "rung_check_max_error": float(np.nanmax(error)) if np.isfinite(error).any() else np.nan,
             "rung_check_rung": st.rung, "rung_check_reference": f"{rc.REFERENCE_RUNG} ({rc.REFERENCE_SCHEME})",
             "rung_check_reused_points": ch.reuses, "rung_check_failed_corners": failed,
             "rung_check_corners_beyond_tolerance": [c.id for c, k in zip(ch.corners, corner_ok) if not k]}
    ds.attrs.update(provenance_attrs(cfg, study=name, model=st.model, mesh_level=st.level,
                                     corners={c.id: c.values for c in ch.corners},
                                     corner_symmetry={c.id: c.symmetry for c in ch.corners}))
    ds.attrs.update({k: v if isinstance(v, (int, float, str)) else json.dumps(v) for k, v in attrs.items()})
    ds.attrs["Conventions"] = "CF-1.8"
    ds.attrs["title"] = f"ureterfsi design study {name}: {st.rung} against {rc.REFERENCE_RUNG} at the corners"
    return ds


RUNG_CHECK_COPIED = ("rung_error", "max_rung_error", "corner_within_tolerance", "corner_rung_wall_time",
                     "corner_reference_wall_time", "rung_tolerance")


def _rung_check_part(st: Study, check) -> tuple[xr.Dataset | None, dict, np.ndarray, np.ndarray]:
    """(the check's variables, its attributes, per point: inside the checked region, trusted) for study_dataset."""
    inside = np.array([st.check.inside(p.values) if st.check else False for p in st.points])
    if check is None:
        if st.check is not None:
            raise ValueError(f"design study {st.name} is checked at its corners: pass its rung check dataset")
        return None, {"rung_check": rung_check_summary(st, np.zeros((0, len(QUANTITIES))), list(inside))}, \
            inside.astype(np.int8), np.zeros(len(st.points), np.int8)
    all_ok = bool(np.asarray(check["corner_within_tolerance"].values).all())
    part = check[list(RUNG_CHECK_COPIED)]
    attrs = {k: v for k, v in check.attrs.items() if k.startswith("rung_check")}
    failed = json.loads(check.attrs.get("rung_check_failed_corners", "{}"))
    attrs["rung_check"] = rung_check_summary(st, check["rung_error"].values, list(inside), failed)   # with the points
    attrs["rung_check_outside_points"] = json.dumps([p.id for p, i in zip(st.points, inside) if not i])
    return part, attrs, inside.astype(np.int8), (inside & all_ok).astype(np.int8)


def study_dataset(cfg: dict, name: str, paths: dict, check: xr.Dataset | None = None):
    """Dataset of a study from its run files {point id: path} and, for a checked study, its rung check
    (rung_check_dataset), whose variables and attributes it takes, with per point whether it lies in the checked
    region and whether it is trusted there (see the module docstring and ureterfsi.rung_check)."""
    st = studies(cfg)[name]
    runs = {p.id: open_netcdf(paths[p.id], DESIGN_RUN) for p in st.points}
    tc = cfg["time"]
    t = np.round(np.arange(0.0, tc["end"] + 0.5 * tc["dt"], tc["dt"]), 9)
    n_hole = max(r.sizes.get("hole", 0) for r in runs.values())
    n = len(st.points)
    data = {k: np.full((n, n_hole) if k in ("peak_hole_flux", "hole_exchange_volume") else n, np.nan) for k in SCALARS}
    series = {k: np.full((n, t.size), np.nan) for k in SERIES}
    hole_series, hole_z = np.full((n, n_hole, t.size), np.nan), np.full((n, n_hole), np.nan)
    hole_axis, hole_side = np.full((n, n_hole), np.nan), np.full((n, n_hole), np.nan)
    for i, p in enumerate(st.points):
        r = runs[p.id]
        for k, v in point_scalars(r).items():
            data[k][i, ...] = v if np.ndim(v) == 0 else np.pad(v, (0, n_hole - len(v)), constant_values=np.nan)
        rt = r["time"].values.astype(float)
        for k in SERIES:
            if k in r or k == "pressure_drop":
                v = pressure_drop(r) if k == "pressure_drop" else r[k].values
                series[k][i] = np.interp(t, rt, v, left=np.nan, right=np.nan)
        for j in range(r.sizes.get("hole", 0)):
            hole_series[i, j] = np.interp(t, rt, r["hole_flux"].values[j], left=np.nan, right=np.nan)
            hole_z[i, j] = float(r["hole_z"].values[j])
            hole_side[i, j] = float(r["hole_side"].values[j])
            hole_axis[i, j] = float(r["hole_axis"].values[j]) if "hole_axis" in r else 1.0
    vars_ = {k: (("design", "hole") if v.ndim == 2 else ("design",), v) for k, v in data.items()}
    vars_ |= {k: (("design", "time"), v) for k, v in series.items()}
    vars_["hole_flux"] = (("design", "hole", "time"), hole_series)
    vars_["model_fraction"] = (("design",), np.array([SYMMETRY_FRACTION[p.symmetry] for p in st.points]))
    vars_ |= mesh_motion_variables(st.points, runs)
    check_part, check_attrs, inside, trusted = _rung_check_part(st, check)
    vars_["in_rung_check_region"] = (("design",), inside)
    vars_["rung_trusted"] = (("design",), trusted)
    coords = {"design": ("design", [p.id for p in st.points]), "time": ("time", t), "hole": ("hole", np.arange(n_hole)),
              "hole_z": (("design", "hole"), hole_z), "hole_side": (("design", "hole"), hole_side),
              "hole_axis": (("design", "hole"), hole_axis)}
    coords |= {q: ("design", [p.values[q] for p in st.points]) for q in st.parameters}
    ds = xr.Dataset(vars_, coords=coords)
    if check_part is not None:
        ds = ds.merge(check_part)
    meta = VARIABLES | {q: DESIGN_PARAMETERS[q] for q in st.parameters} | rung_check_metadata(st.parameters)
    if st.kind == "full_factorial":
        if len(st.parameters) == 1:   # one parameter: a plain index, nothing to unstack
            ds = ds.swap_dims(design=st.parameters[0]).drop_vars("design")
        else:
            ds = ds.set_index(design=st.parameters).unstack("design")
        ds = ds.reindex({q: st.grid[q] for q in st.parameters}).transpose(*st.parameters, ...)
        ds["point_id"] = xr.DataArray(np.array([p.id for p in st.points], dtype=object).reshape(
            [len(st.grid[q]) for q in st.parameters]), dims=st.parameters)
    if st.rows:
        index = {p.id: i for i, p in enumerate(st.points)}
        ds["saltelli_point"] = ("saltelli_row", np.array([index[r] for r in st.rows], dtype=np.int32))
        ds = add_sobol_indices(ds, st.parameters, cfg["design_studies"][name]["sample"]["seed"])
    for k in ds.variables:
        if k in meta:
            ds[k].attrs.update(units=meta[k][0], long_name=meta[k][1])
    ds.attrs.update(provenance_attrs(cfg, study=name, design_kind=st.kind, model=st.model, mesh_level=st.level,
                                     rung=st.rung, point_symmetry={p.id: p.symmetry for p in st.points},
                                     base_values=st.base,
                                     points={p.id: p.values for p in st.points},
                                     point_config_hashes={p.id: runs[p.id].attrs.get("config_hash", "") for p in st.points}))
    ds.attrs.update({k: v if isinstance(v, (int, float, str)) else json.dumps(v) for k, v in check_attrs.items()})
    ds.attrs["Conventions"] = "CF-1.8"
    ds.attrs["title"] = f"ureterfsi design study {name}: model {st.model}, {st.kind}, {len(st.points)} points"
    return ds


def standardised_regression_coefficients(ds, parameters, quantity: str) -> tuple[np.ndarray, float]:
    """SRC_j = b_j s_xj / s_y of the least-squares fit y = b0 + sum b_j x_j over the points of `ds` (one point
    dimension), and its R^2."""
    X = np.column_stack([np.asarray(ds[q].values, float) for q in parameters])
    y = np.asarray(ds[quantity].values, float)
    ok = np.isfinite(y)
    X, y = X[ok], y[ok]
    Xs = (X - X.mean(0)) / np.where(X.std(0) > 0, X.std(0), 1.0)
    ys = (y - y.mean()) / (y.std() if y.std() > 0 else 1.0)
    beta, *_ = np.linalg.lstsq(np.c_[np.ones(len(ys)), Xs], ys, rcond=None)
    r2 = 1.0 - float(np.sum((ys - np.c_[np.ones(len(ys)), Xs] @ beta) ** 2)) / max(float(np.sum(ys ** 2)), 1e-300)
    return beta[1:], r2


def design_figure_kinds(st: Study) -> list:
    """The figures of a study: parameters; a map for a full-factorial grid over two or more parameters with two or
    more values; sensitivity for a sample."""
    return (["parameters"] + (["map"] if len(map_parameters(st.grid)) >= 2 else [])
            + (["sensitivity"] if st.kind in ("sobol", "latin_hypercube", "saltelli") else []))


def map_parameters(grid: dict) -> list:
    """The parameters of a full-factorial grid {parameter: values} that a map can span (two or more values)."""
    return [p for p, v in grid.items() if len(v) >= 2]


def sobol_indices(ds, parameters, quantity: str, seed: int = 0) -> dict:
    """First-order and total Sobol' indices S1_j = V[E(y | x_j)] / V(y), ST_j = E[V(y | x_~j)] / V(y) of `quantity`
    over a Saltelli design (y of sample row r: the point saltelli_point[r]; `parameters` in the sample's column
    order), with the half-widths of their 95 % bootstrap confidence intervals (SALib.analyze.sobol); NaN where a
    point has no value or y is constant. Keys: SOBOL_INDICES."""
    from SALib.analyze import sobol

    y = np.asarray(ds[quantity].values, float)[np.asarray(ds["saltelli_point"].values, int)]
    if not np.isfinite(y).all() or np.ptp(y) == 0:
        return {k: np.full(len(parameters), np.nan) for k in SOBOL_INDICES}
    problem = {"num_vars": len(parameters), "names": list(parameters), "bounds": [[0.0, 1.0]] * len(parameters)}
    res = sobol.analyze(problem, y, calc_second_order=True, conf_level=0.95, seed=seed)
    return {k: np.asarray(res[v], float) for k, v in SOBOL_INDICES.items()}


def add_sobol_indices(ds, parameters, seed: int = 0, quantities=QUANTITIES):
    """`ds` with the Sobol' indices (sobol_indices) of each of `quantities` it holds, on (quantity, parameter)."""
    qs = [q for q in quantities if q in ds]
    res = [sobol_indices(ds, parameters, q, seed) for q in qs]
    data = {k: (("quantity", "parameter"), np.array([r[k] for r in res], float).reshape(len(qs), len(parameters)))
            for k in SOBOL_INDICES}
    return ds.assign(data).assign_coords(quantity=("quantity", qs), parameter=("parameter", list(parameters)))
