"""Runs of a configuration: whether one can be made, the sections a solve reads (rule solve's file), the wall's."""
from __future__ import annotations

import json

from .checks import check_run_config
from .errors import ConfigError, fmt
from .occlusion import occlusion_unposable
from .schema import schema_defaults
from .sections import DEFAULTED_RUN_SECTIONS, RUN_SECTIONS


def one_way_unposable(cfg: dict) -> str:
    """Why the one-way rung cannot pose this configuration, '' if it can: a complete occlusion (its r-z wall ignores
    the tie to the stent). choice: refused rather than the r-z wall's inner radius pinned there: the blended wall
    motion would be another problem's."""
    if cfg["geometry"]["occlusion_length"]:
        return ("geometry.occlusion_length > 0: the one-way rung cannot pose a complete occlusion (its r-z wall "
                "ignores the tie to the stent); use fidelity fully_coupled")
    return ""


def unmakeable(cfg: dict, model: str, level: str, symmetry: str) -> str:
    """Why the mesh of `model` at `level` in `symmetry` (and so every run on it) cannot be made, '' if it can: a
    model of `models`, a level of `mesh.levels`, the axisymmetric (r-z) section only of a stent-free model, no
    stent-free model under a complete occlusion, and no quarter model of an offset stent (geometry.stent_offset breaks
    the x = 0 mirror plane)."""
    models, levels = cfg["models"], cfg["mesh"]["levels"]
    if model not in models:
        return f"model {model!r} is not one of models {sorted(models, key=int)}"
    if level not in levels:
        return f"level {level!r} is not one of mesh.levels {list(levels)}"
    if symmetry == "axisymmetric" and models[model]["stent"]:
        free = [m for m in sorted(models, key=int) if not models[m]["stent"]]
        return (f"model {model} has a stent: the axisymmetric (r-z) section is only for the stent-free models "
                f"{free} (side holes break rotational symmetry)")
    if occlusion_unposable(cfg, model):
        return occlusion_unposable(cfg, model)
    if symmetry == "quarter" and models[model]["stent"] and cfg["geometry"]["stent_offset"]:
        return (f"geometry.stent_offset {fmt(cfg['geometry']['stent_offset'])} m breaks the x = 0 mirror plane: "
                f"model {model} has no quarter model; use symmetry half (y >= 0)")
    return ""


def run_config(sections: dict, model: str) -> dict:
    """The configuration of one solve from what run_sections(cfg, model) returned (rule solve's config file):
    those sections, `models` holding the run's model alone, validated (checks.check_run_config: a file edited by
    hand is refused like a configuration file)."""
    want = set(RUN_SECTIONS) | {"model"}
    if not want <= set(sections) <= want | set(DEFAULTED_RUN_SECTIONS):
        raise ConfigError("<run config>", f"must hold the sections {sorted(want)} (and of "
                                          f"{list(DEFAULTED_RUN_SECTIONS)} those off their defaults), got "
                                          f"{sorted(sections)}")
    for name in RUN_SECTIONS:
        missing = sorted(set(schema_defaults(name)) - set(sections[name]))
        if missing:
            raise ConfigError(f"<run config> {name}.{missing[0]}", "missing: the file was written by another version "
                              "of ureterfsi (re-run rule solve_config)")
    cfg = ({k: sections[k] for k in RUN_SECTIONS} | {k: sections.get(k, schema_defaults(k))
                                                     for k in DEFAULTED_RUN_SECTIONS}
           | {"models": {model: sections["model"]}})
    levels = cfg["mesh"].get("levels") if isinstance(cfg["mesh"], dict) else None
    if isinstance(levels, dict) and all(isinstance(lv, dict) and isinstance(lv.get("size_factor"), (int, float))
                                        for lv in levels.values()):
        # a JSON object has no order (provenance.write_json sorts its keys): the levels, coarse to fine in the
        # configuration, back in that order
        cfg["mesh"] = cfg["mesh"] | {"levels": dict(sorted(levels.items(), key=lambda kv: -kv[1]["size_factor"]))}
    check_run_config(cfg, RUN_SECTIONS + DEFAULTED_RUN_SECTIONS + ("models",))
    return cfg


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
