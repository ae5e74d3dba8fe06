"""A configuration validated (schema, then CHECKS, then its design studies) and loaded from files."""
from __future__ import annotations

import copy

from ureterfsi import REPO_ROOT

from .checks import check_config
from .errors import ConfigError
from .reading import deep_merge, read_yaml
from .occlusion import occlusion_unposable
from .runs import unmakeable

DEFAULT_CONFIG = REPO_ROOT / "config" / "config.yaml"


def check_study_runs_makeable(cfg: dict) -> None:
    """Every study run (each model at study.level in its symmetry: study.runs, else mesh.symmetry) can be made
    (runs.unmakeable, the rule the dry run applies to a target): a configuration whose own runs cannot be made is
    refused by `config check` too, not only when Snakemake plans them. Not part of check_config: a design point
    takes its symmetry from its own geometry (designs.space.point_symmetry), not from mesh.symmetry."""
    for model in sorted(cfg["models"], key=int):
        if occlusion_unposable(cfg, model):
            continue   # kept in the configuration (model 1 is the stability scene's); its mesh is refused
        over = cfg["study"]["runs"].get(model, {})
        why = unmakeable(cfg, model, cfg["study"]["level"], over.get("symmetry", cfg["mesh"]["symmetry"]))
        if why:
            raise ConfigError(f"study.runs.{model}.symmetry" if "symmetry" in over else "mesh.symmetry", why)


def validate_config(cfg: dict) -> None:
    """Validate `cfg` (schema, then CHECKS: checks.check_config; then that its study runs can be made; then its
    design studies); raise ConfigError on the first violation."""
    check_config(cfg)
    check_study_runs_makeable(cfg)
    from ureterfsi.designs.expand import check_design_studies   # the designs read this package: imported on use

    check_design_studies(cfg)


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
