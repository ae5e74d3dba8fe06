"""What the stability rules (workflow/rules/stability.smk) ask of a case, as plain functions of the configuration
and the case's name: its mesh, the rung its reservation is a study solve's on, and the configuration entering it
(its rerun trigger)."""
from __future__ import annotations

import json

from ureterfsi.stability.cases import case_by_name, case_setup
from ureterfsi.workflow import paths

# the configuration sections a case reads (a change re-runs it; plotting options do not)
SECTIONS = ("geometry", "fluid", "ureter", "stent", "peristalsis", "time", "solver")


def case_mesh(cfg: dict, name: str) -> str | list:
    """The r-z mesh of the case's level (case_setup names a level missing from mesh.levels); none for a
    hole_elements case, whose mesh sizes are its own (built in the case)."""
    s = case_setup(cfg, case_by_name(cfg, name))
    if s["scene"] == "holes":
        return []
    return paths.mesh("axisymmetric", s["model"], s["level"])


def case_rung(cfg: dict, name: str) -> tuple[str, str, str]:
    """(fidelity, symmetry, level) of the study solve whose memory a case reserves: r-z fully coupled, or 3D
    one-way at the case's level and symmetry (a hole_elements case)."""
    s = case_setup(cfg, case_by_name(cfg, name))
    if s["scene"] == "holes":
        return "one_way", s["symmetry"], s["level"]
    return "fully_coupled", "axisymmetric", s["level"]


def case_trigger(cfg: dict, name: str) -> str:
    """The configuration entering one case, as JSON (the `stability` section but its axes, the case's axis and
    value, its model, and for a hole_elements case its mesh section)."""
    case = case_by_name(cfg, name)
    s = case_setup(cfg, case)
    mesh = {"mesh": s["cfg"]["mesh"]} if s["scene"] == "holes" else {}
    stability = {k: v for k, v in cfg["stability"].items() if k != "axes"}
    return json.dumps({k: cfg[k] for k in SECTIONS} | mesh
                      | {"stability": stability, "axis": case.axis, "value": case.value,
                         "model": cfg["models"][s["model"]]}, sort_keys=True)
