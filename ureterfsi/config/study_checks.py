"""Cross-key checks of the sections that plan the study rather than pose one solve: `study` (its level, convergence
model and time, its runs), `ladder`, `figures` and `stability` name levels, models and probe times that exist."""
from __future__ import annotations

from ureterfsi.stability.naming import Case

from .errors import RTOL, ConfigError, fmt


def check_study(cfg):
    st = cfg["study"]
    if st["level"] not in cfg["mesh"]["levels"]:
        raise ConfigError("study.level", f"must be one of mesh.levels {sorted(cfg['mesh']['levels'])}, "
                                         f"got {fmt(st['level'])}")
    if st["convergence_model"] not in cfg["models"]:
        raise ConfigError("study.convergence_model", f"must be one of models {sorted(cfg['models'])}, "
                                                     f"got {fmt(st['convergence_model'])}")
    if not cfg["models"][st["convergence_model"]]["stent"]:
        raise ConfigError("study.convergence_model", f"model {st['convergence_model']!r} has no stent: the mesh-"
                                                     f"convergence study (paper §3.1, Fig. 3) compares the stent's "
                                                     f"von Mises stress along the probe line; name a stented model")
    if not any(abs(st["convergence_time"] - t) < 1e-12 for t in cfg["time"]["probe_times"]):
        raise ConfigError("study.convergence_time", f"must be one of time.probe_times "
                                                    f"{fmt(cfg['time']['probe_times'])}, got {fmt(st['convergence_time'])}")


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
        raise ConfigError("ladder.model", f"must be one of models {sorted(cfg['models'])}, got {fmt(lad['model'])}")
    if lad["reference"] not in lad["rungs"]:
        raise ConfigError("ladder.reference", f"must be one of ladder.rungs {sorted(lad['rungs'])}, "
                                              f"got {fmt(lad['reference'])}")
    for name, rung in lad["rungs"].items():
        if rung["level"] not in cfg["mesh"]["levels"]:
            raise ConfigError(f"ladder.rungs.{name}.level", f"must be one of mesh.levels "
                                                            f"{sorted(cfg['mesh']['levels'])}, got {fmt(rung['level'])}")
        if rung["symmetry"] == "axisymmetric" and cfg["models"][lad["model"]]["stent"]:
            raise ConfigError(f"ladder.rungs.{name}.symmetry", f"'axisymmetric' needs a model without stent; "
                                                               f"ladder.model {lad['model']} has one")
        if rung["dt"] > lad["end"]:
            raise ConfigError(f"ladder.rungs.{name}.dt", f"must be <= ladder.end = {fmt(lad['end'])} s, "
                                                         f"got {fmt(rung['dt'])}")
    first = cfg["time"]["probe_times"][0]
    if not lad["end"] >= first * (1 - RTOL):
        raise ConfigError("ladder.end", f"must be >= the first of time.probe_times, {fmt(first)} s (the snapshot "
                                        f"quantities are compared at the probe times within the window), "
                                        f"got {fmt(lad['end'])}")


def check_figures(cfg):
    f, probes = cfg["figures"], cfg["time"]["probe_times"]
    for key in ("wave_times", "hole_velocity_times"):
        for i, t in enumerate(f[key]):
            if not any(abs(t - p) < 1e-12 for p in probes):
                raise ConfigError(f"figures.{key}[{i}]", f"must be one of time.probe_times {fmt(probes)} "
                                                        f"(the snapshots are taken there), got {fmt(t)}")
    if "domain_model" in f and f["domain_model"] not in cfg["models"]:
        raise ConfigError("figures.domain_model", f"must be one of models {sorted(cfg['models'], key=int)}, "
                                                  f"got {fmt(f['domain_model'])}")


def check_stability(cfg):
    """The `stability` section names existing levels and models fit for its scenes (ureterfsi.stability):
    the r-z scene a stent-free model, the hole_elements axis a model with side holes; distinct case names."""
    st = cfg.get("stability")
    if st is None:
        return
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
        raise ConfigError("stability.end", f"must be > time.dt = {fmt(cfg['time']['dt'])} s (the baseline case's "
                                           f"time step), got {fmt(st['end'])}")
    for i, dt in enumerate(st["axes"].get("time_step", [])):
        if not dt < st["end"]:
            raise ConfigError(f"stability.axes.time_step[{i}]",
                              f"must be < stability.end = {fmt(st['end'])} s, got {fmt(dt)}")
    seen = {"baseline": "the baseline"}
    for axis, values in st["axes"].items():
        for i, v in enumerate(values):
            key, name = f"stability.axes.{axis}[{i}]", Case(axis, v).name
            if name in seen:
                raise ConfigError(key, f"{fmt(v)} gives the case name {name!r} of {seen[name]} (values are "
                                       f"named to 3 significant digits)")
            seen[name] = f"stability.axes.{axis}[{i}]"
