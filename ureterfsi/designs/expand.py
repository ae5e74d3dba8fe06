"""Expansion of the design studies (config `design_studies`, ureterfsi.designs.space): each study's points drawn
(grid or sample) and validated, its rung-check corners, the run paths and requests of the workflow's design rules,
once per configuration."""
from __future__ import annotations

import itertools
import math

import numpy as np

from ureterfsi.config.checks import check_config
from ureterfsi.config.occlusion import occlusion_unposable
from ureterfsi.config.errors import ConfigError, fmt
from ureterfsi.config.reading import deep_merge
from ureterfsi.config.sections import mesh_sections, run_sections, wall_sections
from ureterfsi.designs import rung_check as rc
from ureterfsi.designs.space import (ARRANGEMENT, CONFIG_KEYS, FRENCH, FRENCH_RANGE, PARAMETERS, Point,
                                     RESERVED_NAMES, RungCheck, Study, _round, _short_hash, apply, base_values,
                                     map_parameters, point_id, point_symmetry, run_rung)
from ureterfsi.workflow import paths


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


def study_config(cfg: dict, spec: dict) -> dict:
    """The configuration a study's points, corners and references start from: `cfg` (without design_studies) with
    the study's `base` overlay (e.g. its end conditions, its occlusion) merged on top."""
    return deep_merge({k: v for k, v in cfg.items() if k != "design_studies"}, spec.get("base") or {})


def on_rung(cfg: dict, model: str, rung: str) -> dict:
    """`cfg` with its study runs on `rung` (study.fidelity, and `model`'s study.runs override): the configuration
    checks that refuse a scene on the one-way rung (an occlusion, end pressures) see the rung the point is solved on."""
    cfg["study"]["fidelity"] = rung
    if "fidelity" in cfg["study"]["runs"].get(model, {}):
        cfg["study"]["runs"][model]["fidelity"] = rung
    return cfg


def _checked(cfg: dict, model: str, key: str, what: str) -> None:
    """check_config(cfg) and the occlusion's posability on `model`; ConfigError naming `key`, `what` (it cannot be
    posed ...) and why."""
    try:
        check_config(cfg)
    except ConfigError as err:
        raise ConfigError(key, f"{what}: {err.key}: {err.constraint}") from None
    why = occlusion_unposable(cfg, model)
    if why:
        raise ConfigError(key, f"{what}: {why}")


def _check_study(cfg: dict, name: str, spec: dict) -> None:
    key = f"design_studies.{name}"
    if name in RESERVED_NAMES:
        raise ConfigError(key, f"the name is reserved for {paths.DESIGNS}/{name}/; choose another")
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
    if spec.get("base"):
        try:
            cfg = on_rung(study_config(cfg, spec), model, spec.get("rung") or run_rung(cfg, model)[0])
            check_config(cfg)
        except ConfigError as err:
            raise ConfigError(f"design_studies.{name}.base", f"{err.key}: {err.constraint}") from None
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
        pcfg = on_rung(apply(cfg, model, values), model, rung)
        pcfg["solver"]["one_way_mesh_motion"] = spec.get("one_way_mesh_motion", pcfg["solver"]["one_way_mesh_motion"])
        try:
            check_config(pcfg)
        except ConfigError as err:
            raise ConfigError(_parameter_key(name, spec, _blame(values, err)),
                              f"point {pid} ({_values_text(values)}) cannot be posed: {err.key}: {err.constraint}") from None
        why = occlusion_unposable(pcfg, model)
        if why:
            blamed = next((q for q in ("occlusion_position", "occlusion_length") if q in values), next(iter(values)))
            raise ConfigError(_parameter_key(name, spec, blamed),
                              f"point {pid} ({_values_text(values)}) cannot be posed: {why}")
        symmetry = point_symmetry(pcfg, base_symmetry)
        study.points.append(Point(pid, values, pcfg, _short_hash(mesh_sections(pcfg, model, spec["level"], symmetry)),
                                  _short_hash(wall_sections(pcfg)) if rung == "one_way" else None, symmetry,
                                  model, rung))
    study.check = expand_rung_check(cfg, name, spec, study)
    study.references = expand_references(cfg, name, spec, study)
    study.field_points = expand_field_figures(name, spec, study)
    return study


def expand_field_figures(name: str, spec: dict, study: Study) -> list:
    """The ids of the points design_studies.<study>.field_figures selects, each entry the values of some of the
    study's parameters that match exactly one point (within 1e-9 relative); ConfigError naming the entry when it
    names another parameter, matches no point or several, or selects a point without field files to draw from (an
    r-z or stent-free model, fields.enabled false)."""
    out = []
    for i, sel in enumerate(spec.get("field_figures") or []):
        key = f"design_studies.{name}.field_figures.{i}"
        unknown = sorted(set(sel) - set(study.parameters))
        if unknown:
            raise ConfigError(f"{key}.{unknown[0]}", f"must be a parameter of the study {study.parameters}")
        hits = [p for p in study.points if all(math.isclose(p.values[k], v, rel_tol=1e-9, abs_tol=1e-15)
                                               for k, v in sel.items())]
        if len(hits) != 1:
            raise ConfigError(key, f"must select exactly one design point, selects {len(hits)} ({_values_text(sel)})")
        p = hits[0]
        if p.symmetry == "axisymmetric" or not p.config["models"][p.model]["stent"]:
            raise ConfigError(key, f"point {p.id} ({_values_text(p.values)}) has no side holes in 3D to draw "
                                   f"(model {p.model}, {p.symmetry})")
        if not p.config["fields"]["enabled"]:
            raise ConfigError(key, f"point {p.id} writes no field files (fields.enabled: false)")
        if p.id not in out:
            out.append(p.id)
    return out


def expand_references(cfg: dict, name: str, spec: dict, study: Study) -> list:
    """The study's reference runs (design_studies.<study>.references: each a named overlay on the study's
    configuration, on its own model and rung; e.g. the unstented and the stented unobstructed segment under the
    study's end conditions), each a Point named by the hash of its entry."""
    out = []
    for i, ref in enumerate(spec.get("references") or []):
        key = f"design_studies.{name}.references.{i}"
        model = ref.get("model", study.model)
        if model not in cfg["models"]:
            raise ConfigError(f"{key}.model", f"must be one of models {sorted(cfg['models'], key=int)}, "
                                              f"got {fmt(model)}")
        fidelity, base_symmetry = run_rung(cfg, model)
        rung = ref.get("rung", study.rung)
        rcfg = on_rung(deep_merge(cfg, ref.get("overlay") or {}), model, rung)
        _checked(rcfg, model, key, f"reference {ref['name']} (model {model}) cannot be posed")
        symmetry = point_symmetry(rcfg, base_symmetry)
        if rung == "one_way" and symmetry == "axisymmetric":
            raise ConfigError(f"{key}.rung", f"one_way needs a 3D mesh; model {model} runs {symmetry}")
        out.append(Point(_short_hash({"reference": ref}), {}, rcfg,
                         _short_hash(mesh_sections(rcfg, model, study.level, symmetry)),
                         _short_hash(wall_sections(rcfg)) if rung == "one_way" else None, symmetry, model, rung,
                         ref["name"]))
    names = [r.name for r in out]
    if len(set(names)) != len(names):
        raise ConfigError(f"design_studies.{name}.references", f"names must be distinct, got {names}")
    return out


def _space(spec: dict, names: list, all_values: list) -> tuple[dict, dict]:
    """(low, high) of the study's design space: a sample's bounds, else the points' extremes."""
    if "sample" in spec:
        b = spec["sample"]["bounds"]
        return {p: _round(b[p][0]) for p in names}, {p: _round(b[p][1]) for p in names}
    return rc.ranges(all_values, names)


def expand_rung_check(cfg: dict, name: str, spec: dict, study: Study) -> RungCheck | None:
    """The corners of study `name` (ureterfsi.designs.rung_check), each a Point on the segment with its configuration,
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
                      rc.centre(low, high, study.base), opts["on_failure"])
    base_symmetry = run_rung(cfg, study.model)[1]
    for values in rc.corner_values(mode, low, high, study.base):
        values = {p: _round(v) for p, v in values.items()}
        cid = point_id(values)
        ccfg = on_rung(apply(seg, study.model, values), study.model, study.rung)
        ccfg["solver"]["one_way_mesh_motion"] = spec.get("one_way_mesh_motion", ccfg["solver"]["one_way_mesh_motion"])
        _checked(ccfg, study.model, key,
                 f"corner {cid} ({_values_text(values)}) cannot be posed on the segment {opts['segment']}")
        symmetry = point_symmetry(ccfg, base_symmetry)
        if symmetry == "axisymmetric":
            raise ConfigError(key, f"the fully coupled reference of corner {cid} needs a 3D mesh; model "
                                   f"{study.model} runs axisymmetric")
        corner = Point(cid, values, ccfg, _short_hash(mesh_sections(ccfg, study.model, study.level, symmetry)),
                       _short_hash(wall_sections(ccfg)) if study.rung == "one_way" else None, symmetry, study.model,
                       study.rung)
        check.corners.append(corner)
        same = next((p for p in study.points if p.id == cid), None)
        if same is not None and (same.mesh_id, same.symmetry) == (corner.mesh_id, corner.symmetry) and \
                run_sections(same.config, study.model, study.rung) == run_sections(ccfg, study.model, study.rung):
            check.reuses[cid] = same.id
    return check


def corner_run_paths(st: Study) -> dict:
    """{corner id: (run file on the study's rung, fully coupled run file)} of a checked study; the rung's run of
    a corner that is one of the study's points (on its segment) is that point's."""
    if st.check is None:
        return {}
    return {c.id: (paths.design_run(st.name, st.check.reuses[c.id]) if c.id in st.check.reuses
                   else paths.corner_run(st.name, c.id, st.rung), paths.corner_run(st.name, c.id, rc.REFERENCE_RUNG))
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


def points_and_corners(st: Study) -> list:
    """Every Point of a study that needs a mesh: its points, its references and its rung check's corners."""
    return st.points + st.references + (st.check.corners if st.check else [])


def mesh_request(cfg: dict, mesh_id: str) -> tuple[dict, str, str, str]:
    """(configuration, model, level, symmetry) of a design mesh, from the first point (or corner) that uses it."""
    for st in studies(cfg).values():
        for p in points_and_corners(st):
            if p.mesh_id == mesh_id:
                return p.config, p.model, st.level, p.symmetry
    raise KeyError(f"no design point uses mesh {mesh_id}")


def wall_config(cfg: dict, wall_id: str) -> dict:
    """Configuration of a design wall motion, from the first point (or corner) that uses it."""
    for st in studies(cfg).values():
        for p in points_and_corners(st):
            if p.wall_id == wall_id:
                return p.config
    raise KeyError(f"no design point uses wall motion {wall_id}")


def design_figure_kinds(st: Study) -> list:
    """The figures of a study: parameters; a map for a full-factorial grid over two or more parameters with two or
    more values; sensitivity for a sample; passage (per hole against its position) for a study of the whole passage:
    a stented one with a complete occlusion or reference runs."""
    passage = (bool(st.references) or any(p.config["geometry"]["occlusion_length"] > 0 for p in st.points)) and \
        st.points[0].config["models"][st.model]["stent"]
    return (["parameters"] + (["map"] if len(map_parameters(st.grid)) >= 2 else [])
            + (["sensitivity"] if st.kind in ("sobol", "latin_hypercube", "saltelli") else [])
            + (["passage"] if passage else []))


