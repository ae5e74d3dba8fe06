"""A configuration validated (schema, then CHECKS, then its design studies) and loaded from files."""
from __future__ import annotations

import copy

from .. import designs
from .checks import check_config
from .errors import ConfigError
from .reading import deep_merge, read_yaml
from .schema import REPO_ROOT

DEFAULT_CONFIG = REPO_ROOT / "config" / "config.yaml"


def validate_config(cfg: dict) -> None:
    """Validate `cfg` (schema, then CHECKS: checks.check_config; then its design studies); raise ConfigError on
    the first violation."""
    check_config(cfg)
    designs.check_design_studies(cfg)


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
