"""A study run in parts (ureterfsi.designs.status): each point's state from its run file or checkpoint, the done
points' scalars, and a checkpoint without its record named."""
from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
import yaml

from ureterfsi.config import load_config
from ureterfsi.data.checked import BadFile
from ureterfsi.designs import status
from ureterfsi.designs.expand import studies
from ureterfsi.study.run import write_failed_run
from ureterfsi.workflow import paths
from helpers.design_runs import fake_run, grid

REPO = Path(__file__).resolve().parents[2]
BASE = yaml.safe_load((REPO / "config" / "config.yaml").read_text())


def study_tree(tmp_path: Path):
    """A 4-point study: one point done, one failed, one with a checkpoint at 1.5 s, one not begun."""
    cfg = load_config(BASE, {"design_studies": {"s": grid(hole_diameter=[5e-4, 6e-4], peak_traction=[4e4, 5e4])}})
    st = studies(cfg)["s"]
    done, failed, resumable, _ = st.points
    for p in (done, failed):
        (tmp_path / paths.design_run("s", p.id)).parent.mkdir(parents=True)
    fake_run(tmp_path / paths.design_run("s", done.id), 2e-9, 1e-3)
    write_failed_run(failed.config, tmp_path / paths.design_run("s", failed.id), "one_way", "ALE mesh inverted")
    ckpt = tmp_path / paths.checkpoint(f"designs/s/{resumable.id}").replace(".npz", ".rank0of1.npz")
    ckpt.parent.mkdir(parents=True)
    np.savez(ckpt, meta=np.array(json.dumps({"step": 150, "time": 1.5})))
    return cfg, st, ckpt


def test_states_and_scalars_of_a_study_in_parts(tmp_path):
    cfg, st, _ = study_tree(tmp_path)
    rows = status.study_status(cfg, "s", tmp_path)
    assert [r.id for r in rows] == [p.id for p in st.points]
    assert [r.state for r in rows] == ["done", "failed: ALE mesh inverted", "resumes at t = 1.5 s",
                                       "no run file, no checkpoint"]
    # the fake run's outlet flow 2e-9 x (0, 1, 0.5) at 0, 0.02, 0.04 s: trapezoids (0.01 + 0.015) x 2e-9 / 0.04 s
    assert rows[0].scalars["mean_outlet_flux"] == pytest.approx(1.25e-9, rel=1e-12)
    assert rows[0].label == "hole_diameter=0.0005, peak_traction=40000"
    text = status.table(rows)
    assert "| 1.25e-09 |" in text and text.endswith("1 of 4 done")


def test_a_checkpoint_without_its_record_is_named(tmp_path):
    cfg, _, ckpt = study_tree(tmp_path)
    np.savez(ckpt, meta=np.array(json.dumps({"step": 150})))
    with pytest.raises(BadFile, match=f"{ckpt.name}.*checkpoint without its meta record"):
        status.study_status(cfg, "s", tmp_path)


def test_a_corrupt_run_file_is_named(tmp_path):
    cfg, st, _ = study_tree(tmp_path)
    bad = tmp_path / paths.design_run("s", st.points[0].id)
    bad.write_bytes(b"not netCDF")
    with pytest.raises(BadFile, match=f"{bad.name}.*not a netCDF file"):
        status.study_status(cfg, "s", tmp_path)


def test_a_results_root_without_results_is_refused(tmp_path):
    """--results-root names the folder that holds results/: given results/ itself (or any folder without it), the
    command says so instead of reporting every point as not begun."""
    (tmp_path / "results").mkdir()
    with pytest.raises(SystemExit, match=r"--results-root .*results: holds no results/ folder"):
        status.main([str(REPO / "config" / "config.yaml"), "--results-root", str(tmp_path / "results")])
