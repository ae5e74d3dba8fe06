"""Cross-key consistency checks of a schema-valid configuration that poses a solve (geometry, models, time, mesh,
peristalsis, ureter material), the order every check runs in (CHECKS; RUN_CHECKS for one solve), and check_config:
the schema, then CHECKS. The occlusion's checks are in occlusion, the end conditions' in ends, those of the sections
that plan the study in study_checks."""
from __future__ import annotations

import math

from ureterfsi.mesh.geometry import StentModel, UreterGeometry, hole_pair_positions
from ureterfsi.config.ranges import SHEAR_MODULUS

from .ends import check_ends
from .errors import RTOL, ConfigError, fmt
from .occlusion import check_occlusion, check_occlusion_rungs
from .plausible import check_plausible, implausible
from .schema import validate_schema
from .study_checks import check_figures, check_ladder, check_runs, check_stability, check_study

# Bounds of the consistency checks (documented in the messages).
MIN_GAP_HOLE_DIAMETERS = 2.0     # fluid gap stent-ureter >= 2 hole diameters (a hole jet has room to develop)
MIN_ELEMENTS = {"hole": "hole_diameter", "stent_wall": "stent_wall_thickness",   # mesh size -> geometry
                "ureter_wall": "ureter_wall_thickness"}
START_WIDTHS = 3.0               # pulse centre may start at most 3 widths upstream of the inlet
MIN_BULK_RATIO = 10.0            # kappa / (C10 + C01) >= 10: nearly incompressible (paper §2.3.2)
MIN_GAP_ELEMENTS = 2.0           # fluid-bulk elements across the narrowest fluid gap, at the coarsest level


# Each check takes the schema-valid config and raises ConfigError(key, constraint) on failure.

def _geom(cfg) -> UreterGeometry:
    return UreterGeometry.from_config(cfg)


def check_ureter_wall(cfg):
    g = cfg["geometry"]
    ro, t = 0.5 * g["ureter_outer_diameter"], g["ureter_wall_thickness"]
    if not t < ro:
        raise ConfigError("geometry.ureter_wall_thickness",
                          f"must be < the ureter outer radius {fmt(ro)} m (ureter_outer_diameter/2), got {fmt(t)}")


def check_hole_vs_stent(cfg):
    g = cfg["geometry"]
    d, so = g["hole_diameter"], g["stent_inner_diameter"] + 2 * g["stent_wall_thickness"]
    if not d < so:
        raise ConfigError("geometry.hole_diameter",
                          f"must be < the stent outer diameter {fmt(so)} m, got {fmt(d)}")
    # A radial channel of radius a cuts the lumen wall as a simple through-hole only if a < stent inner
    # radius (geometry.hole_channel_volume assumes it).
    if not d < g["stent_inner_diameter"]:
        raise ConfigError("geometry.hole_diameter",
                          f"must be < the stent inner diameter {fmt(g['stent_inner_diameter'])} m "
                          f"(radial through-hole), got {fmt(d)}")


def check_fluid_gap(cfg):
    geo, g = _geom(cfg), cfg["geometry"]
    gap = geo.ureter_inner_radius - geo.stent_outer_radius
    need = MIN_GAP_HOLE_DIAMETERS * g["hole_diameter"]
    if not gap >= need * (1 - RTOL):
        raise ConfigError("geometry.stent_wall_thickness",
                          f"fluid gap between stent outer radius {fmt(geo.stent_outer_radius)} m "
                          f"(stent_inner_diameter/2 + stent_wall_thickness) and ureter inner radius "
                          f"{fmt(geo.ureter_inner_radius)} m is {fmt(gap)} m; need >= "
                          f"{fmt(MIN_GAP_HOLE_DIAMETERS)} hole diameters = {fmt(need)} m")


def check_hole_end_clearance(cfg):
    g = cfg["geometry"]
    c, r, L = g["hole_end_clearance"], 0.5 * g["hole_diameter"], g["length"]
    if not c > r:
        raise ConfigError("geometry.hole_end_clearance",
                          f"must be > the hole radius {fmt(r)} m so every hole lies wholly inside the stent, "
                          f"got {fmt(c)}")
    if not g["hole_diameter"] < L - 2 * c:
        raise ConfigError("geometry.hole_end_clearance",
                          f"the hole positions are clipped to [c, L - c] = [{fmt(c)}, {fmt(L - c)}] m; "
                          f"this span must exceed the hole diameter {fmt(g['hole_diameter'])} m, got c = {fmt(c)}")


# ---- stricture (ureterfsi.mesh.geometry.Stricture)

def check_stricture(cfg):
    """A stricture (fraction > 0) lies inside the segment and keeps the narrowest gap (stent to wall, or the lumen
    radius without a stent) >= geometry.stricture_min_gap of the unobstructed one."""
    g, geo = cfg["geometry"], _geom(cfg)
    if not geo.strictured:
        return
    st, L = geo.stricture, g["length"]
    if not (st.position - 0.5 * st.length >= 0.0 and st.position + 0.5 * st.length <= L):
        raise ConfigError("geometry.stricture_position",
                          f"the stricture [{fmt(st.position - 0.5 * st.length)}, {fmt(st.position + 0.5 * st.length)}] m "
                          f"(stricture_position -+ stricture_length/2) must lie inside the segment [0, {fmt(L)}] m")
    stented = any(m["stent"] for m in cfg["models"].values())
    r_stent = geo.stent_outer_radius if stented else 0.0
    gap, open_gap = geo.narrowest_radius - r_stent, geo.ureter_inner_radius - r_stent
    if not gap >= g["stricture_min_gap"] * open_gap * (1 - RTOL):
        what = "stent outer radius" if stented else "axis"
        raise ConfigError("geometry.stricture_fraction",
                          f"{fmt(st.fraction)} narrows the lumen to radius {fmt(geo.narrowest_radius)} m, a gap of "
                          f"{fmt(gap)} m to the {what}; need >= geometry.stricture_min_gap {fmt(g['stricture_min_gap'])}"
                          f" x the unobstructed {fmt(open_gap)} m (no contact)")


def check_stent_offset(cfg):
    """An offset stent (geometry.stent_offset) keeps the narrowest stent-wall gap, R_i(1 - f) - r_o - |x_s|,
    >= geometry.stent_offset_min_gap of the coaxial annulus R_i - r_o."""
    g, geo = cfg["geometry"], _geom(cfg)
    if not geo.stent_offset:
        return
    gap, open_gap = geo.narrowest_radius - geo.stent_outer_radius - abs(geo.stent_offset), \
        geo.ureter_inner_radius - geo.stent_outer_radius
    if not gap >= g["stent_offset_min_gap"] * open_gap * (1 - RTOL):
        raise ConfigError("geometry.stent_offset",
                          f"{fmt(geo.stent_offset)} m leaves a stent-wall gap of {fmt(gap)} m; need >= "
                          f"geometry.stent_offset_min_gap {fmt(g['stent_offset_min_gap'])} x the coaxial {fmt(open_gap)} m")


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
                                  f"must be 0 for a model without a stent (stent: false), got {fmt(s)}")
            continue
        if s <= 0:
            raise ConfigError(f"{key}.hole_pair_spacing", f"must be > 0 for a stented model (stent: true), got {fmt(s)}")
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
                          f"{fmt(L)} m contradicts the hole counts of models {', '.join(off)}: n pairs at spacing s "
                          f"span the segment end to end, (n-1)s <= L < ns (Table 1), which every stented model "
                          f"meets for L in [{fmt(lo)}, {fmt(hi)}) m")
    for name in stented:
        m, key = cfg["models"][name], f"models.{name}"
        s, holes = m["hole_pair_spacing"], m["holes"]
        n = _pairs(L, s)
        if holes // 2 != n:
            raise ConfigError(f"{key}.holes",
                              f"{holes} holes = {holes // 2} pairs, but spacing {fmt(s)} m over length {fmt(L)} m "
                              f"gives floor(L/s) + 1 = {n} pairs ({2 * n} holes): n pairs at spacing s span the "
                              f"segment end to end, (n-1)s <= L (Table 1)")
        z = hole_pair_positions(geo, StentModel.from_config(cfg, name))
        dz = z[1:] - z[:-1]
        if dz.size and not dz.min() > d:
            i = int(dz.argmin())
            raise ConfigError(f"{key}.hole_pair_spacing",
                              f"hole pairs at z = {fmt(float(z[i]))} and {fmt(float(z[i + 1]))} m overlap: "
                              f"distance {fmt(float(dz[i]))} m must be > hole_diameter {fmt(d)} m "
                              f"(positions clip(k*s, c, L-c), spacing {fmt(s)} m)")


def check_time(cfg):
    t = cfg["time"]
    end, dt, probes = t["end"], t["dt"], t["probe_times"]
    if not dt < end:
        raise ConfigError("time.dt", f"must be < time.end = {fmt(end)} s, got {fmt(dt)}")
    for i, p in enumerate(probes):
        if not 0 < p <= end * (1 + RTOL):
            raise ConfigError(f"time.probe_times[{i}]", f"must lie in (0, time.end = {fmt(end)}] s, got {fmt(p)}")
    for i in range(1, len(probes)):
        if not probes[i] > probes[i - 1]:
            raise ConfigError(f"time.probe_times[{i}]",
                              f"probe times must be strictly increasing, got {fmt(probes[i])} after "
                              f"{fmt(probes[i - 1])}")
    gaps = [b - a for a, b in zip([0.0] + list(probes), probes)]
    if not dt <= min(gaps) * (1 + RTOL):
        raise ConfigError("time.dt",
                          f"must be <= the smallest spacing of the probe times (from t = 0) {fmt(min(gaps))} s, "
                          f"got {fmt(dt)}")
    ramp = cfg["peristalsis"]["ramp_time"]
    if not ramp < end:
        raise ConfigError("peristalsis.ramp_time", f"must be < time.end = {fmt(end)} s, got {fmt(ramp)}")


def check_mesh_sizes(cfg):
    sizes = cfg["mesh"]["sizes"]
    order = ["hole", "stent_wall", "ureter_wall", "fluid_bulk"]
    for a, b in zip(order, order[1:]):
        if not sizes[a] <= sizes[b]:
            raise ConfigError(f"mesh.sizes.{b}",
                              f"must be >= mesh.sizes.{a} = {fmt(sizes[a])} m (hole <= stent_wall <= ureter_wall "
                              f"<= fluid_bulk), got {fmt(sizes[b])}")


def check_levels(cfg):
    levels = cfg["mesh"]["levels"]
    prev = None
    for name, lv in levels.items():
        f = lv["size_factor"]
        if prev is not None and not f < prev[1]:
            raise ConfigError(f"mesh.levels.{name}.size_factor",
                              f"must be < the size_factor {fmt(prev[1])} of the preceding level '{prev[0]}' "
                              f"(levels are listed coarse to fine), got {fmt(f)}")
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
                                  f"at level '{name}' (size_factor {fmt(f)}) geometry.{geo_key} / "
                                  f"(mesh.sizes.{size_key} * size_factor) = {fmt(g[geo_key])} / "
                                  f"({fmt(sizes[size_key])} * {fmt(f)}) = {n:.3g} elements; need >= {fmt(need)} "
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
                          f"at level '{name}' (size_factor {fmt(f)}) the fluid gap {fmt(gap)} m ({what}) / "
                          f"(mesh.sizes.fluid_bulk * size_factor) = {fmt(gap)} / ({fmt(sizes['fluid_bulk'])} * "
                          f"{fmt(f)}) = {n:.3g} elements; need >= {fmt(MIN_GAP_ELEMENTS)} (an element must fit "
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
                          f"must lie in [-{fmt(START_WIDTHS)} widths, L] = [{fmt(lo)}, {fmt(L)}] m, "
                          f"got {fmt(p['start_position'])}")


def check_ureter_material(cfg):
    u = cfg["ureter"]
    mu0 = 2 * (u["c10"] + u["c01"])
    if not mu0 > 0:
        raise ConfigError("ureter.c10",
                          f"Mooney-Rivlin initial shear modulus 2(c10 + c01) must be > 0, got 2({fmt(u['c10'])} + "
                          f"{fmt(u['c01'])}) = {fmt(mu0)} Pa")
    if not SHEAR_MODULUS.low <= mu0 <= SHEAR_MODULUS.high:
        raise ConfigError("ureter.c10", f"Mooney-Rivlin initial shear modulus 2(c10 + c01) = 2({fmt(u['c10'])} + "
                                        f"{fmt(u['c01'])}): {implausible(mu0, SHEAR_MODULUS)}")
    ratio = u["bulk_modulus"] / (u["c10"] + u["c01"])
    if not ratio >= MIN_BULK_RATIO:
        raise ConfigError("ureter.bulk_modulus",
                          f"must be >= {fmt(MIN_BULK_RATIO)} (c10 + c01) for near-incompressibility (paper §2.3.2), "
                          f"got {fmt(u['bulk_modulus'])} Pa = {ratio:.3g} (c10 + c01)")


CHECKS = (
    check_plausible,
    check_ureter_wall, check_hole_vs_stent, check_fluid_gap, check_hole_end_clearance, check_stricture, check_occlusion,
    check_stent_offset,
    check_model_keys, check_models, check_time, check_mesh_sizes, check_levels, check_resolution,
    check_fluid_bulk, check_symmetry, check_peristalsis, check_ureter_material, check_study,
    check_runs, check_occlusion_rungs, check_ladder, check_figures, check_stability, check_ends,
)


# the checks that read only the sections of one solve (runs.RUN_SECTIONS and `models`, holding the run's model)
RUN_CHECKS = (
    check_plausible,
    check_ureter_wall, check_hole_vs_stent, check_fluid_gap, check_hole_end_clearance, check_stricture, check_occlusion,
    check_stent_offset,
    check_models, check_time, check_mesh_sizes, check_levels, check_resolution, check_fluid_bulk, check_peristalsis,
    check_ureter_material, check_ends,
)


def check_run_config(cfg, sections: tuple) -> None:
    """Validate the configuration of one solve (runs.run_config: `sections`, `models` holding the run's model):
    the schema of those sections, then RUN_CHECKS; raise ConfigError on the first violation."""
    validate_schema(cfg, sections)
    for check in RUN_CHECKS:
        check(cfg)


def check_config(cfg) -> None:
    """Validate one configuration, its design studies aside (as each design point is validated): the schema,
    then CHECKS in order; raise ConfigError on the first violation.

    Normalises `cfg` in place first: strings in YAML 1.2 number syntax where the schema expects a number
    become floats (PyYAML/Snakemake read ``5.0e4`` as a string), and missing optional keys get their schema
    defaults (schema.validate_schema).
    """
    if not isinstance(cfg, dict):
        raise ConfigError("<root>", f"must be a mapping, got {type(cfg).__name__}")
    validate_schema(cfg)
    for check in CHECKS:
        check(cfg)
