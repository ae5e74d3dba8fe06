"""The shipped Sobol' study config/designs/obstruction_sobol.yaml (docs/sensitivity.md) on the 10 mm segment: it
validates, expands to SALib's Saltelli design of N (2 D + 2) rows within its bounds with the ids its results were
computed under, and its dry run lists one solve per point and nothing else. No solves."""
from __future__ import annotations

import hashlib
from pathlib import Path

import numpy as np

from ureterfsi.config.reading import deep_merge, read_yaml
from ureterfsi.config.validation import load_config_files
from ureterfsi.designs.expand import saltelli_unit_sample, studies

REPO = Path(__file__).resolve().parents[2]
FILES = [REPO / "config/config.yaml", REPO / "config/segment-10mm.yaml", REPO / "config/designs/obstruction_sobol.yaml"]
NAME = "obstruction_sobol"
BOUNDS = {"stricture_fraction": (0.0, 0.6), "hole_diameter": (5e-4, 9e-4), "wall_stiffness_scale": (0.5, 1.5)}
# SHA-256 (first 16 hex digits) of the point ids of the 64 rows in SALib's order, as run for docs/sensitivity.md
ROWS_SHA = "4617ae5cbd4da3ce"


def study():
    return studies(load_config_files(FILES))[NAME]


def test_shipped_saltelli_study_expands_to_its_points():
    st = study()
    n, d = 8, 3
    assert (st.kind, st.model, st.level, st.rung) == ("saltelli", "2", "coarse", "one_way")
    assert st.parameters == list(BOUNDS) and len(st.rows) == n * (2 * d + 2) == 64
    assert len(st.points) == 64                                  # D = 3: no row repeats
    assert len({p.mesh_id for p in st.points}) == 32             # the stiffness changes no mesh (A, A_B3 share)
    assert len({p.wall_id for p in st.points}) == 32             # the hole diameter changes no wall (A, A_B2)
    assert {p.symmetry for p in st.points} == {"quarter"}
    lo, hi = (np.array([b[i] for b in BOUNDS.values()]) for i in (0, 1))
    unit = saltelli_unit_sample(d, n, 13)
    values = {p.id: [p.values[q] for q in BOUNDS] for p in st.points}
    assert np.allclose([values[r] for r in st.rows], lo + unit * (hi - lo), rtol=1e-9, atol=0)
    for p in st.points:                                          # the held stricture, the model's holes
        g = p.config["geometry"]
        assert (g["stricture_length"], g["stricture_position"], g["length"]) == (0.004, 0.005, 0.010)
        assert p.config["models"]["2"]["holes"] == 6 and p.config["solver"]["one_way_mesh_motion"] == "auto"
    assert hashlib.sha256(" ".join(st.rows).encode()).hexdigest()[:16] == ROWS_SHA


def test_dry_run_of_the_shipped_saltelli_study(tmp_path):
    from helpers.design_runs import dry_run

    cfg = {}
    for f in FILES:                                              # the overlays as the command line merges them
        cfg = deep_merge(cfg, read_yaml(f))
    counts = dry_run(tmp_path, cfg, f"design_{NAME}")
    # and the rung check at the 8 corners of the bounds (on the study's own 10 mm segment: 4 meshes and 4 walls of
    # their own, since no sample point sits at a corner), each on the one-way rung and fully coupled
    assert counts == {"design_solve": 64, "design_mesh": 32 + 4, "design_wall_motion": 32 + 4, "design_dataset": 1,
                      "design_corner_solve": 2 * 8, "design_rung_check": 1, "design_figures": 1, "design_sensitivity": 1,
                      f"design_{NAME}": 1}, counts
