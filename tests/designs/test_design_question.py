"""ureterfsi.designs.question: the spacing's effect on the outlet flow, per combination of a study's other
parameters, from a study dataset built from run files whose outlet flows differ by known amounts."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import xarray as xr
import yaml

from ureterfsi.config import load_config
from ureterfsi.config.reading import deep_merge
from ureterfsi.data import cf as metadata
from ureterfsi.data.provenance import FORMAT_VERSION, FORMAT_VERSION_ATTR
from ureterfsi.designs import question
from ureterfsi.designs.expand import studies
from ureterfsi.designs.results import study_dataset

REPO = Path(__file__).resolve().parents[2]


def _run(path: Path, q: np.ndarray, t: np.ndarray) -> None:
    """A run file whose outlet flux is q(t)."""
    one = np.ones(t.size)
    ds = xr.Dataset({"outlet_flux": ("time", q), "max_wall_displacement": ("time", 1e-5 * one),
                     "min_ale_jacobian": ("time", one)},
                    coords={"time": ("time", t)}, attrs={"wall_time_s": 1.0, "config_hash": "x"})
    metadata.annotate(ds)
    ds.attrs[FORMAT_VERSION_ATTR] = FORMAT_VERSION
    ds.to_netcdf(path)


def test_spread_and_volumes_of_the_spacings_at_each_stent_size(tmp_path, capsys):
    """The shipped voiding_reflux grid (3 sizes x 3 spacings): at each size the outlet flux is
    Q = A sin(2 pi t / T) + b_s, so the spread is (max b - min b) / (A + max |b|) and the net volume of spacing s is
    b_s T; one size's spacings agree exactly (spread 0). The table names the study's ends and each size. The run
    files' times are summed steps, the last one short of T: the dataset still has their value at T."""
    from helpers.design_runs import stamp

    cfg = load_config(deep_merge(yaml.safe_load((REPO / "config" / "config.yaml").read_text()),
                                 yaml.safe_load((REPO / "config" / "designs" / "voiding_reflux.yaml").read_text())))
    st = studies(cfg)["voiding_reflux"]
    T = cfg["time"]["end"]
    t = np.concatenate([[0.0], np.cumsum(np.full(300, T / 300))])    # as the solver sums its steps: t[-1] < T
    assert t[-1] < T
    A = 2e-7
    offset = {0.005: 0.0, 0.010: 1e-9, 0.025: 4e-9}
    sizes = sorted({p.values["stent_outer_diameter"] for p in st.points})
    paths = {}
    for p in st.points + st.references:
        paths[p.id] = tmp_path / f"{p.id}.nc"
        same = p.values.get("stent_outer_diameter") == sizes[0]
        b = 0.0 if same or p not in st.points else offset[p.values["hole_pair_spacing"]]
        _run(paths[p.id], A * np.sin(2 * np.pi * t / T) + b, t)
    ds = study_dataset(cfg, "voiding_reflux", stamp(st, paths))

    assert np.isfinite(ds["outlet_flux"].values).all()                  # the last step on the grid's t = T
    rows = question.spacing_effects(ds)
    assert len(rows) == len(sizes)
    by_size = {r.values["stent_outer_diameter"]: r for r in rows}
    assert sorted(by_size) == sizes
    np.testing.assert_allclose(by_size[sizes[0]].outlet_flux_spread, 0.0, atol=1e-12)
    for d in sizes[1:]:
        r = by_size[d]
        assert r.spacings == [0.005, 0.010, 0.025] and r.window == (0.0, T)
        np.testing.assert_allclose(r.outlet_flux_spread, 4e-9 / (A + 4e-9), rtol=1e-3)
        np.testing.assert_allclose(r.outlet_volumes, [0.0, 1e-9 * T, 4e-9 * T], atol=1e-12)
        assert "ends: kidney pelvis, bladder voiding" in r.condition and "stent_outer_diameter" in r.condition

    path = tmp_path / "voiding_reflux.nc"
    metadata.write_netcdf(ds, path)
    question.main([str(path)])
    out = capsys.readouterr().out.splitlines()
    assert out[0].startswith("| study | scene |") and len(out) == 2 + len(sizes)
    assert all(line.startswith("| voiding_reflux |") for line in out[2:])
    question.write_table([path], tmp_path / "question.md")            # rule design_question's output
    assert (tmp_path / "question.md").read_text().splitlines()[2:] == out


def test_a_study_without_the_spacing_gives_no_row():
    ds = xr.Dataset({"outlet_flux": (("occlusion_position", "time"), np.ones((2, 3)))},
                    coords={"time": np.arange(3.0), "occlusion_position": [0.0045, 0.0055]})
    assert question.spacing_effects(ds) == []


def test_spread_without_flow_is_nan():
    assert np.isnan(question.outlet_flux_spread(np.zeros((3, 4))))
    np.testing.assert_allclose(question.outlet_flux_spread(np.array([[1.0, -2.0], [1.5, -2.0]])), 0.25)


def test_dry_run_asks_the_datasets_of_the_studies_varying_the_spacing(tmp_path):
    """design_question takes the dataset of each full-factorial study varying the spacing, and only those."""
    from helpers.design_runs import dry_run, grid
    from helpers.snakemake_runs import e2e_config

    cfg = e2e_config(tmp_path / "base.yaml")
    cfg["design_studies"] = {"a": grid(model="2", hole_pair_spacing=[0.005, 0.01]),
                             "b": grid(model="2", hole_pair_spacing=[0.005, 0.01], hole_diameter=[5e-4, 7e-4]),
                             "c": grid(model="2", hole_diameter=[5e-4, 7e-4])}
    counts = dry_run(tmp_path, cfg, "design_question")
    assert counts["design_question"] == 1 and counts["design_dataset"] == 2, counts
    assert counts["design_solve"] == 6, counts
