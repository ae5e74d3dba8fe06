"""Validated study configuration (config/config.yaml).

Two layers, both reported as one line ``config error: <dotted.key>: <constraint, with the value>``:

1. JSON Schema (workflow/schemas/config.schema.yaml): keys, types, ranges, enums, no unknown keys.
   Of several violations the first by dotted key path (sorted) is reported, so the message is
   deterministic. Optional keys with a schema ``default`` are filled in place (as
   ``snakemake.utils.validate(..., set_default=True)`` would), so every consumer sees the same keys.
   An integer key is refused as a float even when integral (``15.0``): JSON Schema's ``integer`` accepts
   15.0, but a float where a count is meant reaches the engine as a float.
2. Physical/geometric consistency (``CHECKS``, run in order, first failure reported): plausible
   magnitudes first (``ureterfsi.config.ranges``: a value outside its range is most often a unit slip),
   then the cross-key rules the schema cannot express. Each check is a small function naming the key it
   blames; where a rule involves several keys the message quotes every value entering it.

Files are read by ``read_yaml`` (PyYAML's safe loader, YAML 1.1 as Snakemake reads them), which also refuses
what that loader lets through silently: a key given twice in one mapping, a decimal comma in a flow mapping
(``{s: 0,005}`` reads as ``{s: 0, 5: null}``) or sequence, a leading-zero integer (``010`` is octal 8); a
syntax error is reported as ``file:line:column``.

    python -m ureterfsi.config check config/config.yaml [overlay.yaml ...]

Modules by job: errors (ConfigError, fmt, RTOL), reading (YAML files, --config values, deep_merge), schema (layer 1),
plausible, checks, occlusion, ends and study_checks (layer 2: the checks of a solve's sections, the complete
occlusion's, the end conditions', those of the sections that plan the study; checks.check_config: both layers, as
each design point is validated), validation (validate_config: check_config, then the design studies; load_config*),
ranges (the plausible magnitudes), sections (the one list of the sections each job reads: run_sections,
mesh_sections, wall_sections), runs (run_config, unmakeable), cli (the command line).
"""
from __future__ import annotations

from .checks import (CHECKS, MIN_BULK_RATIO, MIN_ELEMENTS, MIN_GAP_ELEMENTS, MIN_GAP_HOLE_DIAMETERS, START_WIDTHS,
                     check_fluid_bulk, check_fluid_gap, check_hole_end_clearance, check_hole_vs_stent, check_levels,
                     check_mesh_sizes, check_model_keys, check_models, check_peristalsis, check_resolution,
                     check_stent_offset, check_stricture, check_symmetry, check_time, check_ureter_material,
                     check_ureter_wall)
from .cli import main
from .ends import check_ends
from .errors import RTOL, ConfigError
from .occlusion import check_occlusion, check_occlusion_rungs, occlusion_unposable
from .plausible import check_plausible
from .reading import deep_merge, read_config_args, read_yaml
from .runs import one_way_unposable, read_run_config, run_config, unmakeable
from .sections import DEFAULTED_RUN_SECTIONS, RUN_SECTIONS, WALL_GEOMETRY, mesh_sections, run_sections, wall_sections
from .schema import REPO_ROOT, SCHEMA_PATH, load_schema, schema_defaults
from .study_checks import check_figures, check_ladder, check_runs, check_stability, check_study
from .validation import DEFAULT_CONFIG, load_config, load_config_files, validate_config

__all__ = [
    "CHECKS", "ConfigError", "DEFAULT_CONFIG", "DEFAULTED_RUN_SECTIONS", "MIN_BULK_RATIO", "MIN_ELEMENTS",
    "MIN_GAP_ELEMENTS", "MIN_GAP_HOLE_DIAMETERS", "REPO_ROOT", "RTOL", "RUN_SECTIONS", "SCHEMA_PATH",
    "START_WIDTHS", "WALL_GEOMETRY", "check_ends", "check_figures", "check_fluid_bulk", "check_fluid_gap",
    "check_hole_end_clearance", "check_hole_vs_stent", "check_ladder", "check_levels", "check_mesh_sizes",
    "check_model_keys", "check_models", "check_occlusion", "check_occlusion_rungs", "check_peristalsis",
    "check_plausible", "check_resolution", "check_runs", "check_stability", "check_stent_offset", "check_stricture",
    "check_study", "check_symmetry", "check_time", "check_ureter_material", "check_ureter_wall", "deep_merge",
    "load_config", "load_config_files", "load_schema", "main", "mesh_sections", "occlusion_unposable",
    "one_way_unposable", "read_config_args", "read_run_config", "read_yaml", "run_config", "run_sections",
    "schema_defaults", "unmakeable", "validate_config", "wall_sections",
]
