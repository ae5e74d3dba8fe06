"""Validated study configuration (config/config.yaml).

Two layers, both reported as one line ``config error: <dotted.key>: <constraint, with the value>``:

1. JSON Schema (workflow/schemas/config.schema.yaml): keys, types, ranges, enums, no unknown keys.
   Of several violations the first by dotted key path (sorted) is reported, so the message is
   deterministic. Optional keys with a schema ``default`` are filled in place (as
   ``snakemake.utils.validate(..., set_default=True)`` would), so every consumer sees the same keys.
   An integer key is refused as a float even when integral (``15.0``): JSON Schema's ``integer`` accepts
   15.0, but a float where a count is meant reaches the engine as a float.
2. Physical/geometric consistency (``CHECKS`` below, run in order, first failure reported): plausible
   magnitudes first (``ureterfsi.plausibility``: a value outside its range is most often a unit slip),
   then the cross-key rules the schema cannot express. Each check is a small function naming the key it
   blames; where a rule involves several keys the message quotes every value entering it.

Files are read by ``read_yaml`` (PyYAML's safe loader, YAML 1.1 as Snakemake reads them), which also refuses
what that loader lets through silently: a key given twice in one mapping, a decimal comma in a flow mapping
(``{s: 0,005}`` reads as ``{s: 0, 5: null}``) or sequence, a leading-zero integer (``010`` is octal 8); a
syntax error is reported as ``file:line:column``.

    python -m ureterfsi.config check config/config.yaml [overlay.yaml ...]
"""
from __future__ import annotations

import copy
import json
import math
import re
import sys
from functools import lru_cache
from pathlib import Path

import yaml

from ureterfsi.geometry import StentModel, UreterGeometry, hole_pair_positions
from ureterfsi.plausibility import SHEAR_MODULUS, Range, range_of, unit_slip

REPO_ROOT = Path(__file__).resolve().parent.parent
SCHEMA_PATH = REPO_ROOT / "workflow" / "schemas" / "config.schema.yaml"
DEFAULT_CONFIG = REPO_ROOT / "config" / "config.yaml"

RTOL = 1e-9  # relative slack of the floating-point comparisons of exact design ratios (e.g. 0.5/0.125 = 4)

# Bounds of the consistency checks (documented in the messages).
MIN_GAP_HOLE_DIAMETERS = 2.0     # fluid gap stent-ureter >= 2 hole diameters (a hole jet has room to develop)
MIN_ELEMENTS = {"hole": "hole_diameter", "stent_wall": "stent_wall_thickness",   # mesh size -> geometry
                "ureter_wall": "ureter_wall_thickness"}
START_WIDTHS = 3.0               # pulse centre may start at most 3 widths upstream of the inlet
MIN_BULK_RATIO = 10.0            # kappa / (C10 + C01) >= 10: nearly incompressible (paper §2.3.2)
MIN_GAP_ELEMENTS = 2.0           # fluid-bulk elements across the narrowest fluid gap, at the coarsest level


class ConfigError(ValueError):
    """An invalid configuration; ``str`` is one line naming the key and the violated constraint."""

    def __init__(self, key: str, constraint: str):
        self.key = key
        self.constraint = " ".join(str(constraint).split())  # one line, whatever went in
        super().__init__(f"config error: {key}: {self.constraint}")


def _fmt(v) -> str:
    if isinstance(v, bool) or v is None:
        return repr(v)
    if isinstance(v, float):
        return f"{v:g}"
    if isinstance(v, (list, tuple)):
        return "[" + ", ".join(_fmt(x) for x in v) + "]"
    return repr(v)


# --------------------------------------------------------------------------------------- schema layer

@lru_cache(maxsize=1)
def load_schema() -> dict:
    return yaml.safe_load(SCHEMA_PATH.read_text())


def _dotted(parts) -> str:
    out = ""
    for p in parts:
        out += f"[{p}]" if isinstance(p, int) else (f".{p}" if out else str(p))
    return out or "<root>"


def _prescan(node, path=()) -> None:
    """Refuse what JSON Schema cannot see in YAML data: non-string keys and non-finite numbers."""
    if isinstance(node, dict):
        for k, v in node.items():
            if not isinstance(k, str):
                raise ConfigError(_dotted(path + (str(k),)),
                                  f"keys must be strings, got {type(k).__name__} {k!r} (quote it: \"{k}\")")
            _prescan(v, path + (k,))
    elif isinstance(node, list):
        for i, v in enumerate(node):
            _prescan(v, path + (i,))
    elif isinstance(node, float) and not math.isfinite(node):
        raise ConfigError(_dotted(path), f"must be a finite number, got {node}")


def _fill_defaults(node, schema: dict) -> None:
    """Insert schema defaults of missing optional keys (in place), recursing into present objects."""
    if not isinstance(node, dict):
        return
    for key, sub in schema.get("properties", {}).items():
        if key not in node and "default" in sub:
            node[key] = copy.deepcopy(sub["default"])
        if key in node:
            _fill_defaults(node[key], sub)
    for pattern, sub in schema.get("patternProperties", {}).items():
        for key, value in node.items():
            if isinstance(key, str) and re.search(pattern, key):
                _fill_defaults(value, sub)


# YAML 1.2 (and JSON) read 5.0e4 as a number; PyYAML, and with it Snakemake's config loader, implement
# YAML 1.1, whose float syntax needs a dot and a signed exponent, so 5.0e4 arrives as the string '5.0e4'.
_YAML12_FLOAT = re.compile(r"[-+]?(\.[0-9]+|[0-9]+(\.[0-9]*)?)([eE][-+]?[0-9]+)?")
_DECIMAL_COMMA = re.compile(r"[-+]?[0-9]*,[0-9]+")


def _resolve(schema: dict, root: dict) -> dict:
    ref = schema.get("$ref", "")
    if ref.startswith("#/$defs/"):
        return {**root["$defs"][ref.split("/")[-1]], **{k: v for k, v in schema.items() if k != "$ref"}}
    return schema


def _coerce_numbers(node, schema: dict, root: dict):
    """Convert (in place) strings in YAML 1.2 number syntax where the schema expects a number."""
    schema = _resolve(schema, root)
    if isinstance(node, dict):
        subs = schema.get("properties", {})
        pats = schema.get("patternProperties", {})
        for k, v in node.items():
            sub = subs.get(k) or next((ps for p, ps in pats.items() if isinstance(k, str) and re.search(p, k)), None)
            if sub is not None:
                node[k] = _coerce_numbers(v, sub, root)
    elif isinstance(node, list) and isinstance(schema.get("items"), dict):
        node[:] = [_coerce_numbers(v, schema["items"], root) for v in node]
    elif isinstance(node, str) and schema.get("type") == "number" and _YAML12_FLOAT.fullmatch(node.strip()):
        return float(node)
    return node


def _schema_message(err) -> tuple[str, str]:
    """(dotted key, one-line constraint) of a jsonschema ValidationError."""
    path = list(err.absolute_path)
    v, val, inst = err.validator, err.validator_value, err.instance
    if v == "required":
        missing = [k for k in val if isinstance(inst, dict) and k not in inst]
        return _dotted(path + [missing[0]]), "required key is missing"
    if v == "additionalProperties":
        props = err.schema.get("properties", {})
        patterns = list(err.schema.get("patternProperties", {}))
        extra = sorted(k for k in inst if k not in props and not any(re.search(p, k) for p in patterns))
        allowed = (f"allowed keys: {', '.join(props)}" if props else
                   f"keys must match {' or '.join(patterns)}")
        return _dotted(path + [extra[0]]), f"unknown key (misspelt?); {allowed}"
    if v == "type":
        if val == "integer" and isinstance(inst, float):
            fix = f": write {int(inst)}" if inst.is_integer() else ""
            return _dotted(path), f"must be an integer, got the float {inst!r}{fix}"
        hint = ""
        if val == "number" and isinstance(inst, str) and _DECIMAL_COMMA.fullmatch(inst.strip()):
            hint = f" (decimal comma? write {inst.strip().replace(',', '.')})"
        return _dotted(path), f"must be of type {val}, got {type(inst).__name__} {_fmt(inst)}{hint}"
    ops = {"minimum": ">=", "exclusiveMinimum": ">", "maximum": "<=", "exclusiveMaximum": "<"}
    if v in ops:
        return _dotted(path), f"must be {ops[v]} {_fmt(val)}, got {_fmt(inst)}"
    if v == "enum":
        return _dotted(path), f"must be one of {', '.join(map(str, val))}; got {_fmt(inst)}"
    if v == "multipleOf":
        return _dotted(path), f"must be a multiple of {_fmt(val)}, got {_fmt(inst)}"
    if v in ("minItems", "minProperties"):
        return _dotted(path), f"must have at least {val} entr{'y' if val == 1 else 'ies'}, got {len(inst)}"
    if v == "minLength":
        return _dotted(path), f"must be a non-empty string, got {_fmt(inst)}"
    return _dotted(path), err.message


@lru_cache(maxsize=1)
def _validator():
    """Draft 2020-12 validator of the schema whose ``integer`` excludes floats (JSON Schema accepts 15.0)."""
    from jsonschema import Draft202012Validator, validators

    checker = Draft202012Validator.TYPE_CHECKER.redefine(
        "integer", lambda _, inst: isinstance(inst, int) and not isinstance(inst, bool))
    return validators.extend(Draft202012Validator, type_checker=checker)(load_schema())


def _validate_schema(cfg: dict) -> None:
    errors = [_schema_message(e) for e in _validator().iter_errors(cfg)]
    if errors:
        key, text = min(errors, key=lambda kt: (kt[0].split("."), kt[1]))
        raise ConfigError(key, text)


# ---------------------------------------------------------------------------- consistency checks
# Each check takes the schema-valid config and raises ConfigError(key, constraint) on failure.

def _geom(cfg) -> UreterGeometry:
    return UreterGeometry.from_config(cfg)


def _leaves(node, path=()):
    """(dotted key, value) of every number in the configuration, in its order."""
    if isinstance(node, dict):
        for k, v in node.items():
            yield from _leaves(v, path + (k,))
    elif isinstance(node, list):
        for i, v in enumerate(node):
            yield from _leaves(v, path + (i,))
    elif isinstance(node, (int, float)) and not isinstance(node, bool):
        yield _dotted(path), node


def _implausible(value: float, rng: Range) -> str:
    units = "" if rng.units == "1" else f" {rng.units}"
    slip = unit_slip(value, rng)
    return (f"{_fmt(float(value))}{units} is outside the plausible range [{rng.low:g}, {rng.high:g}]{units} "
            f"({rng.reason}){'; ' + slip if slip else ''}")


def check_plausible(cfg):
    """Every magnitude within its plausible range (ureterfsi.plausibility.RANGES)."""
    for key, value in _leaves(cfg):
        rng = range_of(key)
        if rng is not None and not rng.low <= value <= rng.high:
            raise ConfigError(key, _implausible(value, rng))


def check_ureter_wall(cfg):
    g = cfg["geometry"]
    ro, t = 0.5 * g["ureter_outer_diameter"], g["ureter_wall_thickness"]
    if not t < ro:
        raise ConfigError("geometry.ureter_wall_thickness",
                          f"must be < the ureter outer radius {_fmt(ro)} m (ureter_outer_diameter/2), got {_fmt(t)}")


def check_hole_vs_stent(cfg):
    g = cfg["geometry"]
    d, so = g["hole_diameter"], g["stent_inner_diameter"] + 2 * g["stent_wall_thickness"]
    if not d < so:
        raise ConfigError("geometry.hole_diameter",
                          f"must be < the stent outer diameter {_fmt(so)} m, got {_fmt(d)}")
    # A radial channel of radius a cuts the lumen wall as a simple through-hole only if a < stent inner
    # radius (geometry.hole_channel_volume assumes it).
    if not d < g["stent_inner_diameter"]:
        raise ConfigError("geometry.hole_diameter",
                          f"must be < the stent inner diameter {_fmt(g['stent_inner_diameter'])} m "
                          f"(radial through-hole), got {_fmt(d)}")


def check_fluid_gap(cfg):
    geo, g = _geom(cfg), cfg["geometry"]
    gap = geo.ureter_inner_radius - geo.stent_outer_radius
    need = MIN_GAP_HOLE_DIAMETERS * g["hole_diameter"]
    if not gap >= need * (1 - RTOL):
        raise ConfigError("geometry.stent_wall_thickness",
                          f"fluid gap between stent outer radius {_fmt(geo.stent_outer_radius)} m "
                          f"(stent_inner_diameter/2 + stent_wall_thickness) and ureter inner radius "
                          f"{_fmt(geo.ureter_inner_radius)} m is {_fmt(gap)} m; need >= "
                          f"{_fmt(MIN_GAP_HOLE_DIAMETERS)} hole diameters = {_fmt(need)} m")


def check_hole_end_clearance(cfg):
    g = cfg["geometry"]
    c, r, L = g["hole_end_clearance"], 0.5 * g["hole_diameter"], g["length"]
    if not c > r:
        raise ConfigError("geometry.hole_end_clearance",
                          f"must be > the hole radius {_fmt(r)} m so every hole lies wholly inside the stent, "
                          f"got {_fmt(c)}")
    if not g["hole_diameter"] < L - 2 * c:
        raise ConfigError("geometry.hole_end_clearance",
                          f"the hole positions are clipped to [c, L - c] = [{_fmt(c)}, {_fmt(L - c)}] m; "
                          f"this span must exceed the hole diameter {_fmt(g['hole_diameter'])} m, got c = {_fmt(c)}")


# ---- stricture (issue 13, ureterfsi.geometry.Stricture)

def check_stricture(cfg):
    """A stricture (fraction > 0) lies inside the segment and keeps the narrowest gap (stent to wall, or the lumen
    radius without a stent) >= geometry.stricture_min_gap of the unobstructed one."""
    g, geo = cfg["geometry"], _geom(cfg)
    if not geo.strictured:
        return
    st, L = geo.stricture, g["length"]
    if not (st.position - 0.5 * st.length >= 0.0 and st.position + 0.5 * st.length <= L):
        raise ConfigError("geometry.stricture_position",
                          f"the stricture [{_fmt(st.position - 0.5 * st.length)}, {_fmt(st.position + 0.5 * st.length)}] m "
                          f"(stricture_position -+ stricture_length/2) must lie inside the segment [0, {_fmt(L)}] m")
    stented = any(m["stent"] for m in cfg["models"].values())
    r_stent = geo.stent_outer_radius if stented else 0.0
    gap, open_gap = geo.narrowest_radius - r_stent, geo.ureter_inner_radius - r_stent
    if not gap >= g["stricture_min_gap"] * open_gap * (1 - RTOL):
        what = "stent outer radius" if stented else "axis"
        raise ConfigError("geometry.stricture_fraction",
                          f"{_fmt(st.fraction)} narrows the lumen to radius {_fmt(geo.narrowest_radius)} m, a gap of "
                          f"{_fmt(gap)} m to the {what}; need >= geometry.stricture_min_gap {_fmt(g['stricture_min_gap'])}"
                          f" x the unobstructed {_fmt(open_gap)} m (no contact)")


def check_stent_offset(cfg):
    """An offset stent (geometry.stent_offset, issue 13) keeps the narrowest stent-wall gap, R_i(1 - f) - r_o - |x_s|,
    >= geometry.stent_offset_min_gap of the coaxial annulus R_i - r_o."""
    g, geo = cfg["geometry"], _geom(cfg)
    if not geo.stent_offset:
        return
    gap, open_gap = geo.narrowest_radius - geo.stent_outer_radius - abs(geo.stent_offset), \
        geo.ureter_inner_radius - geo.stent_outer_radius
    if not gap >= g["stent_offset_min_gap"] * open_gap * (1 - RTOL):
        raise ConfigError("geometry.stent_offset",
                          f"{_fmt(geo.stent_offset)} m leaves a stent-wall gap of {_fmt(gap)} m; need >= "
                          f"geometry.stent_offset_min_gap {_fmt(g['stent_offset_min_gap'])} x the coaxial {_fmt(open_gap)} m")


def check_model_keys(cfg):
    keys = sorted(cfg["models"], key=int)
    want = [str(i) for i in range(1, len(keys) + 1)]
    if keys != want:
        raise ConfigError("models", f"model keys must be \"1\"..\"{len(keys)}\" without gaps, got {keys}")


def _pairs(L: float, s: float) -> int:
    """Hole pairs at spacing s spanning a segment of length L end to end: floor(L/s) + 1 (Table 1)."""
    return math.floor(L / s + 1e-9) + 1


def check_models(cfg):
    L, geo = cfg["geometry"]["length"], _geom(cfg)
    d = cfg["geometry"]["hole_diameter"]
    stented = []
    for name in sorted(cfg["models"], key=int):
        m, key = cfg["models"][name], f"models.{name}"
        s, holes = m["hole_pair_spacing"], m["holes"]
        if not m["stent"]:
            if holes != 0:
                raise ConfigError(f"{key}.holes", f"must be 0 for a model without a stent (stent: false), got {holes}")
            if s != 0:
                raise ConfigError(f"{key}.hole_pair_spacing",
                                  f"must be 0 for a model without a stent (stent: false), got {_fmt(s)}")
            continue
        if s <= 0:
            raise ConfigError(f"{key}.hole_pair_spacing", f"must be > 0 for a stented model (stent: true), got {_fmt(s)}")
        if holes <= 0 or holes % 2:
            raise ConfigError(f"{key}.holes",
                              f"must be a positive even number (holes come in radial pairs) for a stented model, "
                              f"got {holes}")
        stented.append(name)
    # (n-1)s <= L < ns for n pairs at spacing s: when several models miss it but agree on an interval of L,
    # the length is what is wrong, not their hole counts
    off = [n for n in stented if cfg["models"][n]["holes"] // 2 != _pairs(L, cfg["models"][n]["hole_pair_spacing"])]
    lo = max(((cfg["models"][n]["holes"] // 2 - 1) * cfg["models"][n]["hole_pair_spacing"] for n in stented),
             default=0.0)
    hi = min((cfg["models"][n]["holes"] // 2 * cfg["models"][n]["hole_pair_spacing"] for n in stented),
             default=math.inf)
    if len(off) >= 2 and lo < hi:
        raise ConfigError("geometry.length",
                          f"{_fmt(L)} m contradicts the hole counts of models {', '.join(off)}: n pairs at spacing s "
                          f"span the segment end to end, (n-1)s <= L < ns (Table 1), which every stented model "
                          f"meets for L in [{_fmt(lo)}, {_fmt(hi)}) m")
    for name in stented:
        m, key = cfg["models"][name], f"models.{name}"
        s, holes = m["hole_pair_spacing"], m["holes"]
        n = _pairs(L, s)
        if holes // 2 != n:
            raise ConfigError(f"{key}.holes",
                              f"{holes} holes = {holes // 2} pairs, but spacing {_fmt(s)} m over length {_fmt(L)} m "
                              f"gives floor(L/s) + 1 = {n} pairs ({2 * n} holes): n pairs at spacing s span the "
                              f"segment end to end, (n-1)s <= L (Table 1)")
        z = hole_pair_positions(geo, StentModel.from_config(cfg, name))
        dz = z[1:] - z[:-1]
        if dz.size and not dz.min() > d:
            i = int(dz.argmin())
            raise ConfigError(f"{key}.hole_pair_spacing",
                              f"hole pairs at z = {_fmt(float(z[i]))} and {_fmt(float(z[i + 1]))} m overlap: "
                              f"distance {_fmt(float(dz[i]))} m must be > hole_diameter {_fmt(d)} m "
                              f"(positions clip(k*s, c, L-c), spacing {_fmt(s)} m)")


def check_time(cfg):
    t = cfg["time"]
    end, dt, probes = t["end"], t["dt"], t["probe_times"]
    if not dt < end:
        raise ConfigError("time.dt", f"must be < time.end = {_fmt(end)} s, got {_fmt(dt)}")
    for i, p in enumerate(probes):
        if not 0 < p <= end * (1 + RTOL):
            raise ConfigError(f"time.probe_times[{i}]", f"must lie in (0, time.end = {_fmt(end)}] s, got {_fmt(p)}")
    for i in range(1, len(probes)):
        if not probes[i] > probes[i - 1]:
            raise ConfigError(f"time.probe_times[{i}]",
                              f"probe times must be strictly increasing, got {_fmt(probes[i])} after "
                              f"{_fmt(probes[i - 1])}")
    gaps = [b - a for a, b in zip([0.0] + list(probes), probes)]
    if not dt <= min(gaps) * (1 + RTOL):
        raise ConfigError("time.dt",
                          f"must be <= the smallest spacing of the probe times (from t = 0) {_fmt(min(gaps))} s, "
                          f"got {_fmt(dt)}")
    ramp = cfg["peristalsis"]["ramp_time"]
    if not ramp < end:
        raise ConfigError("peristalsis.ramp_time", f"must be < time.end = {_fmt(end)} s, got {_fmt(ramp)}")


def check_mesh_sizes(cfg):
    sizes = cfg["mesh"]["sizes"]
    order = ["hole", "stent_wall", "ureter_wall", "fluid_bulk"]
    for a, b in zip(order, order[1:]):
        if not sizes[a] <= sizes[b]:
            raise ConfigError(f"mesh.sizes.{b}",
                              f"must be >= mesh.sizes.{a} = {_fmt(sizes[a])} m (hole <= stent_wall <= ureter_wall "
                              f"<= fluid_bulk), got {_fmt(sizes[b])}")


def check_levels(cfg):
    levels = cfg["mesh"]["levels"]
    prev = None
    for name, lv in levels.items():
        f = lv["size_factor"]
        if prev is not None and not f < prev[1]:
            raise ConfigError(f"mesh.levels.{name}.size_factor",
                              f"must be < the size_factor {_fmt(prev[1])} of the preceding level '{prev[0]}' "
                              f"(levels are listed coarse to fine), got {_fmt(f)}")
        prev = (name, f)


def check_resolution(cfg):
    g, sizes = cfg["geometry"], cfg["mesh"]["sizes"]
    for name, lv in cfg["mesh"]["levels"].items():
        f = lv["size_factor"]
        for size_key, geo_key in MIN_ELEMENTS.items():
            need = cfg["mesh"]["resolution_minima"][size_key]
            n = g[geo_key] / (sizes[size_key] * f)
            if not n >= need * (1 - RTOL):
                raise ConfigError(f"mesh.sizes.{size_key}",
                                  f"at level '{name}' (size_factor {_fmt(f)}) geometry.{geo_key} / "
                                  f"(mesh.sizes.{size_key} * size_factor) = {_fmt(g[geo_key])} / "
                                  f"({_fmt(sizes[size_key])} * {_fmt(f)}) = {n:.3g} elements; need >= {_fmt(need)} "
                                  f"(mesh.resolution_minima.{size_key})")


def check_fluid_bulk(cfg):
    """The fluid-bulk element fits the lumen: >= MIN_GAP_ELEMENTS across the narrowest fluid gap (stent to
    ureter wall; the lumen radius if no model has a stent) at the coarsest level."""
    geo, sizes, levels = _geom(cfg), cfg["mesh"]["sizes"], cfg["mesh"]["levels"]
    stented = any(m["stent"] for m in cfg["models"].values())
    gap = geo.ureter_inner_radius - (geo.stent_outer_radius if stented else 0.0)
    name = max(levels, key=lambda n: levels[n]["size_factor"])
    f = levels[name]["size_factor"]
    n = gap / (sizes["fluid_bulk"] * f)
    if not n >= MIN_GAP_ELEMENTS * (1 - RTOL):
        what = "ureter inner radius - stent outer radius" if stented else "ureter inner radius"
        raise ConfigError("mesh.sizes.fluid_bulk",
                          f"at level '{name}' (size_factor {_fmt(f)}) the fluid gap {_fmt(gap)} m ({what}) / "
                          f"(mesh.sizes.fluid_bulk * size_factor) = {_fmt(gap)} / ({_fmt(sizes['fluid_bulk'])} * "
                          f"{_fmt(f)}) = {n:.3g} elements; need >= {_fmt(MIN_GAP_ELEMENTS)} (an element must fit "
                          f"the lumen)")


def check_symmetry(cfg):
    if cfg["mesh"]["symmetry"] == "axisymmetric":
        stented = [n for n in sorted(cfg["models"], key=int) if cfg["models"][n]["stent"]]
        if stented:
            raise ConfigError("mesh.symmetry",
                              f"'axisymmetric' is study-wide and only valid if no model has a stent (side holes "
                              f"break rotational symmetry); stented models: {', '.join(stented)}")


def check_peristalsis(cfg):
    p, L = cfg["peristalsis"], cfg["geometry"]["length"]
    lo = -START_WIDTHS * p["width"]
    if not lo <= p["start_position"] <= L:
        raise ConfigError("peristalsis.start_position",
                          f"must lie in [-{_fmt(START_WIDTHS)} widths, L] = [{_fmt(lo)}, {_fmt(L)}] m, "
                          f"got {_fmt(p['start_position'])}")


def check_ureter_material(cfg):
    u = cfg["ureter"]
    mu0 = 2 * (u["c10"] + u["c01"])
    if not mu0 > 0:
        raise ConfigError("ureter.c10",
                          f"Mooney-Rivlin initial shear modulus 2(c10 + c01) must be > 0, got 2({_fmt(u['c10'])} + "
                          f"{_fmt(u['c01'])}) = {_fmt(mu0)} Pa")
    if not SHEAR_MODULUS.low <= mu0 <= SHEAR_MODULUS.high:
        raise ConfigError("ureter.c10", f"Mooney-Rivlin initial shear modulus 2(c10 + c01) = 2({_fmt(u['c10'])} + "
                                        f"{_fmt(u['c01'])}): {_implausible(mu0, SHEAR_MODULUS)}")
    ratio = u["bulk_modulus"] / (u["c10"] + u["c01"])
    if not ratio >= MIN_BULK_RATIO:
        raise ConfigError("ureter.bulk_modulus",
                          f"must be >= {_fmt(MIN_BULK_RATIO)} (c10 + c01) for near-incompressibility (paper §2.3.2), "
                          f"got {_fmt(u['bulk_modulus'])} Pa = {ratio:.3g} (c10 + c01)")


def check_study(cfg):
    st = cfg["study"]
    if st["level"] not in cfg["mesh"]["levels"]:
        raise ConfigError("study.level", f"must be one of mesh.levels {sorted(cfg['mesh']['levels'])}, "
                                         f"got {_fmt(st['level'])}")
    if st["convergence_model"] not in cfg["models"]:
        raise ConfigError("study.convergence_model", f"must be one of models {sorted(cfg['models'])}, "
                                                     f"got {_fmt(st['convergence_model'])}")
    if not any(abs(st["convergence_time"] - t) < 1e-12 for t in cfg["time"]["probe_times"]):
        raise ConfigError("study.convergence_time", f"must be one of time.probe_times "
                                                    f"{_fmt(cfg['time']['probe_times'])}, got {_fmt(st['convergence_time'])}")


def check_runs(cfg):
    for model, over in cfg["study"]["runs"].items():
        key = f"study.runs.{model}"
        if model not in cfg["models"]:
            raise ConfigError(key, f"must be a key of models {sorted(cfg['models'])}")
        if over.get("symmetry") == "axisymmetric" and cfg["models"][model]["stent"]:
            raise ConfigError(f"{key}.symmetry", "'axisymmetric' is only valid for a model without stent "
                                                 "(side holes break rotational symmetry)")


def check_ladder(cfg):
    lad = cfg.get("ladder")
    if lad is None:
        return
    if lad["model"] not in cfg["models"]:
        raise ConfigError("ladder.model", f"must be one of models {sorted(cfg['models'])}, got {_fmt(lad['model'])}")
    if lad["reference"] not in lad["rungs"]:
        raise ConfigError("ladder.reference", f"must be one of ladder.rungs {sorted(lad['rungs'])}, "
                                              f"got {_fmt(lad['reference'])}")
    for name, rung in lad["rungs"].items():
        if rung["level"] not in cfg["mesh"]["levels"]:
            raise ConfigError(f"ladder.rungs.{name}.level", f"must be one of mesh.levels "
                                                            f"{sorted(cfg['mesh']['levels'])}, got {_fmt(rung['level'])}")
        if rung["symmetry"] == "axisymmetric" and cfg["models"][lad["model"]]["stent"]:
            raise ConfigError(f"ladder.rungs.{name}.symmetry", f"'axisymmetric' needs a model without stent; "
                                                               f"ladder.model {lad['model']} has one")
        if rung["dt"] > lad["end"]:
            raise ConfigError(f"ladder.rungs.{name}.dt", f"must be <= ladder.end = {_fmt(lad['end'])} s, "
                                                         f"got {_fmt(rung['dt'])}")
    first = cfg["time"]["probe_times"][0]
    if not lad["end"] >= first * (1 - RTOL):
        raise ConfigError("ladder.end", f"must be >= the first of time.probe_times, {_fmt(first)} s (the snapshot "
                                        f"quantities are compared at the probe times within the window), "
                                        f"got {_fmt(lad['end'])}")


def check_figures(cfg):
    f, probes = cfg["figures"], cfg["time"]["probe_times"]
    for key in ("wave_times", "hole_velocity_times"):
        for i, t in enumerate(f[key]):
            if not any(abs(t - p) < 1e-12 for p in probes):
                raise ConfigError(f"figures.{key}[{i}]", f"must be one of time.probe_times {_fmt(probes)} "
                                                        f"(the snapshots are taken there), got {_fmt(t)}")
    if "domain_model" in f and f["domain_model"] not in cfg["models"]:
        raise ConfigError("figures.domain_model", f"must be one of models {sorted(cfg['models'], key=int)}, "
                                                  f"got {_fmt(f['domain_model'])}")


def check_stability(cfg):
    """The `stability` section names existing levels and models fit for its scenes (ureterfsi.stability):
    the r-z scene a stent-free model, the hole_elements axis a model with side holes; distinct case names."""
    st = cfg.get("stability")
    if st is None:
        return
    from ureterfsi.stability.cases import Case

    levels, models = cfg["mesh"]["levels"], cfg["models"]
    if st["level"] not in levels:
        raise ConfigError("stability.level", f"mesh level {st['level']!r} is not one of mesh.levels {list(levels)}")
    for i, level in enumerate(st["axes"].get("mesh_level", [])):
        if level not in levels:
            raise ConfigError(f"stability.axes.mesh_level[{i}]",
                              f"mesh level {level!r} is not one of mesh.levels {list(levels)}")
    if st["model"] not in models:
        raise ConfigError("stability.model", f"must be one of models {sorted(models, key=int)}, got {st['model']!r}")
    if models[st["model"]]["stent"]:
        raise ConfigError("stability.model", f"model {st['model']!r} has a stent: the r-z (axisymmetric) scene "
                                             f"needs a stent-free model")
    if st["axes"].get("hole_elements"):
        model = st["holes"]["model"]
        if model not in models:
            raise ConfigError("stability.holes.model", f"must be one of models {sorted(models, key=int)}, "
                                                       f"got {model!r}")
        if not (models[model]["stent"] and models[model]["holes"]):
            raise ConfigError("stability.holes.model", f"model {model!r} has no side holes: the hole_elements "
                                                       f"axis needs a stented model with holes")
    if not cfg["time"]["dt"] < st["end"]:
        raise ConfigError("stability.end", f"must be > time.dt = {_fmt(cfg['time']['dt'])} s (the baseline case's "
                                           f"time step), got {_fmt(st['end'])}")
    for i, dt in enumerate(st["axes"].get("time_step", [])):
        if not dt < st["end"]:
            raise ConfigError(f"stability.axes.time_step[{i}]",
                              f"must be < stability.end = {_fmt(st['end'])} s, got {_fmt(dt)}")
    seen = {"baseline": "the baseline"}
    for axis, values in st["axes"].items():
        for i, v in enumerate(values):
            key, name = f"stability.axes.{axis}[{i}]", Case(axis, v).name
            if name in seen:
                raise ConfigError(key, f"{_fmt(v)} gives the case name {name!r} of {seen[name]} (values are "
                                       f"named to 3 significant digits)")
            seen[name] = f"stability.axes.{axis}[{i}]"


CHECKS = (
    check_plausible,
    check_ureter_wall, check_hole_vs_stent, check_fluid_gap, check_hole_end_clearance, check_stricture, check_stent_offset,
    check_model_keys, check_models, check_time, check_mesh_sizes, check_levels, check_resolution,
    check_fluid_bulk, check_symmetry, check_peristalsis, check_ureter_material, check_study,
    check_runs, check_ladder, check_figures, check_stability,
)


# ------------------------------------------------------------------------------------------- API

def validate_config(cfg: dict) -> None:
    """Validate `cfg` (schema, then CHECKS); raise ConfigError on the first violation.

    Normalises `cfg` in place first: strings in YAML 1.2 number syntax where the schema expects a number
    become floats (PyYAML/Snakemake read ``5.0e4`` as a string, see _YAML12_FLOAT), and missing optional
    keys get their schema defaults.
    """
    if not isinstance(cfg, dict):
        raise ConfigError("<root>", f"must be a mapping, got {type(cfg).__name__}")
    _coerce_numbers(cfg, load_schema(), load_schema())
    _prescan(cfg)
    _fill_defaults(cfg, load_schema())
    _validate_schema(cfg)
    for check in CHECKS:
        check(cfg)
    from ureterfsi.designs import check_design_studies  # each design point validated as a config of its own
    check_design_studies(cfg)


def unmakeable(cfg: dict, model: str, level: str, symmetry: str) -> str:
    """Why the mesh of `model` at `level` in `symmetry` (and so every run on it) cannot be made, '' if it can: a
    model of `models`, a level of `mesh.levels`, the axisymmetric (r-z) section only of a stent-free model, and no
    quarter model of an offset stent (geometry.stent_offset breaks the x = 0 mirror plane)."""
    models, levels = cfg["models"], cfg["mesh"]["levels"]
    if model not in models:
        return f"model {model!r} is not one of models {sorted(models, key=int)}"
    if level not in levels:
        return f"level {level!r} is not one of mesh.levels {list(levels)}"
    if symmetry == "axisymmetric" and models[model]["stent"]:
        free = [m for m in sorted(models, key=int) if not models[m]["stent"]]
        return (f"model {model} has a stent: the axisymmetric (r-z) section is only for the stent-free models "
                f"{free} (side holes break rotational symmetry)")
    if symmetry == "quarter" and models[model]["stent"] and cfg["geometry"]["stent_offset"]:
        return (f"geometry.stent_offset {_fmt(cfg['geometry']['stent_offset'])} m breaks the x = 0 mirror plane: "
                f"model {model} has no quarter model; use symmetry half (y >= 0)")
    return ""


# the geometry the r-z wall solve reads (ureterfsi.scenes.wall_rz.WallModel): the stent and its holes do not enter
WALL_GEOMETRY = ("length", "ureter_outer_diameter", "ureter_wall_thickness", "stricture_fraction", "stricture_length",
                 "stricture_position")


RUN_SECTIONS = ("geometry", "fluid", "ureter", "stent", "peristalsis", "time", "mesh", "solver", "fields")


def run_sections(cfg: dict, model: str) -> dict:
    """The configuration one solve of `model` reads (RUN_SECTIONS and its entry of `models`): a change re-runs
    the solve (rule `solve`), and a checkpoint made from other values is not resumed (ureterfsi.study)."""
    return {k: cfg[k] for k in RUN_SECTIONS} | {"model": cfg["models"][model]}


def run_config(sections: dict, model: str) -> dict:
    """The configuration of one solve from what run_sections(cfg, model) returned (rule solve's config file):
    those sections, `models` holding the run's model alone."""
    want = set(RUN_SECTIONS) | {"model"}
    if set(sections) != want:
        raise ConfigError("<run config>", f"must hold exactly the sections {sorted(want)}, got {sorted(sections)}")
    for name in RUN_SECTIONS:
        missing = sorted(set(schema_defaults(name)) - set(sections[name]))
        if missing:
            raise ConfigError(f"<run config> {name}.{missing[0]}", "missing: the file was written by another version "
                              "of ureterfsi (re-run rule solve_config)")
    return {k: sections[k] for k in RUN_SECTIONS} | {"models": {model: sections["model"]}}


def read_run_config(path, model: str) -> dict:
    """run_config of the JSON file rule solve_config wrote; ConfigError naming the file when it is not one."""
    try:
        with open(path) as fh:
            sections = json.load(fh)
    except (OSError, ValueError) as err:
        raise ConfigError(f"<run config> {path}", f"unreadable ({err})") from None
    if not isinstance(sections, dict):
        raise ConfigError(f"<run config> {path}", "must be a JSON object of configuration sections")
    try:
        return run_config(sections, model)
    except ConfigError as err:
        raise ConfigError(f"<run config> {path}: {err.key.removeprefix('<run config>').strip()}",
                          err.constraint) from None


def wall_sections(cfg: dict) -> dict:
    """The configuration the one-way rung's r-z wall solve reads (ureterfsi.study.oneway.wall_history): a change
    re-runs the shared wall-motion job, and a wall-motion file made from other values is refused."""
    return {"geometry": {k: cfg["geometry"][k] for k in WALL_GEOMETRY}} | {
        k: cfg[k] for k in ("ureter", "peristalsis", "time")} | {
        "solver": {k: cfg["solver"][k] for k in ("predictor", "max_step_halvings")}}


def deep_merge(base: dict, overrides: dict) -> dict:
    """Return `base` updated recursively by `overrides` (nested dicts merged, other values replaced)."""
    out = copy.deepcopy(base)
    for k, v in (overrides or {}).items():
        if isinstance(v, dict) and isinstance(out.get(k), dict):
            out[k] = deep_merge(out[k], v)
        else:
            out[k] = copy.deepcopy(v)
    return out


_INT_TAG, _NULL_TAG, _MERGE_TAG = "tag:yaml.org,2002:int", "tag:yaml.org,2002:null", "tag:yaml.org,2002:merge"
_LEADING_ZERO = re.compile(r"[-+]?0[0-9_]+")   # YAML 1.1: 010 is octal 8, 09 a string


def _plain_number(node) -> bool:
    return (isinstance(node, yaml.ScalarNode) and node.style is None
            and node.tag in (_INT_TAG, "tag:yaml.org,2002:float"))


def _where(name: str, node) -> str:
    return f"{name}:{node.start_mark.line + 1}"


def _between(text: str, a, b) -> str:
    return text[a.end_mark.index:b.start_mark.index]


def _comma_between(text: str, a, b) -> bool:
    return _between(text, a, b).strip() == ","


def _list_decimal_comma(text: str, items: list, i: int) -> bool:
    """Items i-1, i of a flow sequence are one number with a decimal comma: ``[0,005]`` (YAML 1.1: [0, 5], the
    second with a leading zero) or ``[0,5, 1.0]`` (two integers joined by a bare ',' in a list whose other
    separators have a blank; ``[1,2,3]`` is not flagged)."""
    a, b = items[i - 1], items[i]
    if not (_plain_number(a) and _plain_number(b) and b.tag == _INT_TAG and _comma_between(text, a, b)):
        return False
    if _LEADING_ZERO.fullmatch(b.value):
        return True
    return (a.tag == _INT_TAG and _between(text, a, b) == ","
            and any(_between(text, x, y) != "," for x, y in zip(items, items[1:])))


def _check_nodes(node, path: tuple, name: str, text: str) -> None:
    """Refuse what PyYAML reads silently: duplicate keys, decimal commas in flow style, leading-zero ints."""
    if isinstance(node, yaml.MappingNode):
        seen, prev = {}, None
        for knode, vnode in node.value:
            if knode.tag == _MERGE_TAG:
                _check_nodes(vnode, path, name, text)
                continue
            if not isinstance(knode, yaml.ScalarNode):
                _check_nodes(vnode, path + ("?",), name, text)
                continue
            if (node.flow_style and prev is not None and _plain_number(prev[1]) and knode.style is None
                    and re.fullmatch(r"[0-9]+", knode.value) and vnode.tag == _NULL_TAG and vnode.value == ""
                    and _comma_between(text, prev[1], knode)):
                raise ConfigError(_dotted(path + (prev[0],)),
                                  f"decimal comma in {prev[1].value},{knode.value} ({_where(name, knode)}): write "
                                  f"{prev[1].value}.{knode.value} (in a {{...}} mapping a comma separates entries)")
            ident = (knode.tag, knode.value)
            if ident in seen:
                raise ConfigError(_dotted(path + (knode.value,)),
                                  f"key given twice ({seen[ident]} and {_where(name, knode)}); YAML keeps the "
                                  f"second silently: remove one")
            seen[ident] = _where(name, knode)
            _check_nodes(vnode, path + (knode.value,), name, text)
            prev = (knode.value, vnode)
    elif isinstance(node, yaml.SequenceNode):
        for i, item in enumerate(node.value):
            if node.flow_style and i and _list_decimal_comma(text, node.value, i):
                a = node.value[i - 1].value
                raise ConfigError(_dotted(path + (i - 1,)),
                                  f"decimal comma in {a},{item.value} ({_where(name, item)}): write {a}.{item.value} "
                                  f"(in a [...] list a comma separates entries)")
            _check_nodes(item, path + (i,), name, text)
    elif (isinstance(node, yaml.ScalarNode) and node.style is None and node.tag == _INT_TAG
          and _LEADING_ZERO.fullmatch(node.value)):
        raise ConfigError(_dotted(path), f"{node.value} has a leading zero, which YAML 1.1 reads as an octal "
                                         f"number ({_where(name, node)}): write {node.value.lstrip('0') or '0'}")


def _load_yaml(text: str, name: str, path: tuple = ()):
    """The YAML document `text` (None if empty) by PyYAML's safe loader, refusing syntax errors (as
    name:line:column), duplicate keys, decimal commas in flow style and leading-zero integers."""
    loader = yaml.SafeLoader(text)
    try:
        node = loader.get_single_node()
        if node is None:
            return None
        _check_nodes(node, path, name, text)
        return loader.construct_document(node)
    except yaml.MarkedYAMLError as exc:
        mark = exc.problem_mark or exc.context_mark
        where = f"{name}:{mark.line + 1}:{mark.column + 1}" if mark else name
        detail = "; ".join(str(x) for x in (exc.context, exc.problem) if x)
        raise ConfigError(where, f"YAML syntax error: {detail}") from None
    except yaml.YAMLError as exc:
        raise ConfigError(name, f"YAML error: {exc}") from None
    finally:
        loader.dispose()


def read_yaml(path) -> dict:
    """The mapping of a YAML file as Snakemake reads it (PyYAML safe loader), with the refusals of _load_yaml."""
    name = str(path)
    try:
        text = Path(path).read_text()
    except FileNotFoundError:
        raise ConfigError(name, "file not found") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise ConfigError(name, f"cannot read the file: {exc}") from None
    data = _load_yaml(text, name)
    if data is None:
        return {}
    if not isinstance(data, dict):
        raise ConfigError(name, f"must be a YAML mapping of sections, got {type(data).__name__}")
    return data


def read_config_args(entries) -> dict:
    """The overrides of ``snakemake --config KEY=VALUE ...``, each VALUE read like a config file (_load_yaml).
    Snakemake reads a nested VALUE with PyYAML's BaseLoader, every scalar a string: ``solver='{newton_max_iterations:
    20}'`` arrived as '20' and was refused as not an integer, ``mesh='{optimize: false}'`` as not a boolean."""
    out: dict = {}
    for entry in entries or ():
        key, _, text = entry.partition("=")
        out = deep_merge(out, {key: _load_yaml(text.strip("'\""), f"--config {key}", (key,))})
    return out


def schema_defaults(section: str) -> dict:
    """The schema's defaults of a top-level section, as validate_config fills them in."""
    out: dict = {}
    _fill_defaults(out, load_schema()["properties"][section])
    return out


def load_config(path_or_dict=DEFAULT_CONFIG, overrides: dict | None = None) -> dict:
    """Read a YAML file (or copy a dict), deep-merge `overrides`, validate and return the config."""
    base = copy.deepcopy(path_or_dict) if isinstance(path_or_dict, dict) else read_yaml(path_or_dict)
    if not isinstance(base, dict):
        raise ConfigError("<root>", f"must be a mapping, got {type(base).__name__}")
    cfg = deep_merge(base, overrides) if overrides else base
    validate_config(cfg)
    return cfg


def load_config_files(paths) -> dict:
    """Load a configuration file with overlay files deep-merged on top, in order, and validate."""
    cfg = read_yaml(paths[0])
    for overlay in paths[1:]:
        cfg = deep_merge(cfg, read_yaml(overlay))
    return load_config(cfg)


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    if len(argv) < 2 or argv[0] != "check":
        sys.stderr.write("usage: python -m ureterfsi.config check <config.yaml> [<overlay.yaml> ...]\n")
        return 2
    from ureterfsi.provenance import config_hash

    try:
        cfg = load_config_files(argv[1:])
    except ConfigError as err:
        sys.stderr.write(f"{err}\n")
        return 2
    print(f"config ok: {config_hash(cfg)}")
    return 0


if __name__ == "__main__":
    # the package's module, not this __main__ copy, whose ConfigError is another class than the one
    # ureterfsi.designs raises (a design-study error was a traceback)
    from ureterfsi.config import main as package_main

    sys.exit(package_main())
