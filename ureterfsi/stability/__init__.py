"""Stability at the extremes: a one-at-a-time parameter matrix around the baseline (docs/stability.md).

Each case changes one quantity of the configuration's baseline (config `stability.axes`), runs to
`stability.end` and ends "stable" or "failed" at the first limit it hits, with a diagnosis naming the limit,
the time and the place. Two scenes: the stent-free model in r-z, fully coupled (every axis but
hole_elements), and a stented 3D quarter model solved one-way (hole_elements).

naming    the cases' names (Case), plain data the configuration checks share
cases     the axes as data, the cases of a configuration and the configuration of each
limits    the limits and the StabilityLimit a case ends with
observer  energies, volume balance and limits after every accepted step (an engine Observer; dolfinx)
run       run_case: one case -> its dataset, the failure classified from the engine's exceptions and records
jobs      what the stability rules ask of a case: its mesh, reservation rung and rerun trigger
dataset   the per-case scalars (CaseScalars), the per-case file, the combined matrix, its outcome table
"""
from .cases import AXES, AXIS, AXIS_PARAMETER, SCENES, SYMMETRY, Axis, case_by_name, case_setup, cases, settings
from .dataset import CASE_FILE, PER_STEP, SCALARS, SERIES, CaseScalars, combine, outcome_table, write_case
from .limits import LIMITS, StabilityLimit
from .naming import Case, format_value


def __getattr__(name):
    # run (and observer) import dolfinx: config validation and the figures read the rest without it
    if name == "run_case":
        from .run import run_case
        return run_case
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


__all__ = ["AXES", "AXIS", "AXIS_PARAMETER", "Axis", "CASE_FILE", "Case", "CaseScalars", "LIMITS", "PER_STEP",
           "SCALARS", "SCENES", "SERIES", "SYMMETRY", "StabilityLimit", "case_by_name", "case_setup", "cases",
           "combine", "format_value", "outcome_table", "run_case", "settings", "write_case"]
