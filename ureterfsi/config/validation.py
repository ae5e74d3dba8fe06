"""A configuration validated (schema, then CHECKS, then its design studies) and loaded from files."""
from __future__ import annotations

import copy

from .checks import CHECKS
from .errors import ConfigError
from .reading import deep_merge, read_yaml
from .schema import REPO_ROOT, validate_schema

DEFAULT_CONFIG = REPO_ROOT / "config" / "config.yaml"


def validate_config(cfg: dict) -> None:
    """Validate `cfg` (schema, then CHECKS, then its design studies); raise ConfigError on the first violation.

    Normalises `cfg` in place first: strings in YAML 1.2 number syntax where the schema expects a number
    become floats (PyYAML/Snakemake read ``5.0e4`` as a string), and missing optional keys get their schema
    defaults (schema.validate_schema).
    """
    if not isinstance(cfg, dict):
        raise ConfigError("<root>", f"must be a mapping, got {type(cfg).__name__}")
    validate_schema(cfg)
    for check in CHECKS:
        check(cfg)
    # lazy: designs validates each design point with validate_config (a circle)
    from ureterfsi.designs import check_design_studies
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
