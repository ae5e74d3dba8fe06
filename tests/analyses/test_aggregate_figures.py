"""Study datasets and figures from synthetic per-run datasets with the exact structure of
ureterfsi.study.probes.probes_dataset and known analytic values (outlet flux = A sin(t), ...)."""
from __future__ import annotations

import sys

import copy  # noqa: E402
import json

import matplotlib
import numpy as np
import pytest
import xarray as xr

from ureterfsi.analyses import aggregate
from ureterfsi.plotting import paper as plotting
from ureterfsi.plotting.style import figure_paths, save_figure
from ureterfsi.mesh import tags
from ureterfsi.mesh.io import read_msh
from ureterfsi.data.provenance import FORMAT_VERSION, FORMAT_VERSION_ATTR
from ureterfsi.mesh.geometry import StentModel, UreterGeometry, hole_pair_positions
from ureterfsi.data.cf import VARIABLES as CF
from helpers.synthetic import FLUX_AMPLITUDE, VM_BASE, synthetic_run


@pytest.fixture
def runs(tmp_path, cfg):
    """Per-run files of the four models (model 3 with an adaptive step refinement, model 1 axisymmetric)."""
    paths = []
    for m in cfg["models"]:
        sym = "axisymmetric" if m == "1" else "quarter"
        ds = synthetic_run(cfg, m, symmetry=sym, refine=(1.0, 1.2) if m == "3" else None)
        p = tmp_path / "runs" / sym / f"model{m}_coarse.nc"
        p.parent.mkdir(parents=True, exist_ok=True)
        ds.to_netcdf(p)
        paths.append(p)
    return paths


@pytest.fixture
def level_runs(tmp_path, cfg):
    paths = []
    for i, (lv, n) in enumerate(zip(cfg["mesh"]["levels"], (60000, 140000, 320000))):
        p = tmp_path / "conv" / f"model3_{lv}.nc"
        p.parent.mkdir(parents=True, exist_ok=True)
        synthetic_run(cfg, "3", level=lv, end=1.6, level_factor=1 + 0.1 / (i + 1), cells=n).to_netcdf(p)
        paths.append(p)
    return paths[::-1]    # deliberately not in config order


def _check_cf(ds):
    for name, var in ds.variables.items():
        assert "units" in var.attrs and "long_name" in var.attrs, name


def test_synthetic_run_has_probe_structure(cfg):
    ds = synthetic_run(cfg, "2")
    assert set(ds.dims) == {"time", "probe_time", "z", "hole_offset", "hole", "step"}
    assert ds.attrs["model"] == "2" and ds.attrs["symmetry"] == "quarter"
    assert ds.sizes["hole"] == 11   # quarter model: one hole per pair
    for v in ds.data_vars:
        assert v in CF


def test_combine_models(runs, cfg, tmp_path):
    ds = aggregate.combine_models(runs, cfg)
    assert list(ds["model"].values) == ["1", "2", "3", "4"]
    assert list(ds["model_label"].values) == ["No stent", "5 mm", "10 mm", "25 mm"]
    _check_cf(ds)
    assert ds["outlet_flux"].attrs["units"] == "m3 s-1"
    # union grid: every step time of every run; model 3's halved steps are in it
    assert 1.005 in np.round(ds["time"].values, 9)
    assert "union" in ds.attrs["time_grid_description"] and ds.attrs["time_interpolation"] == "linear"
    # linear interpolation of the other models onto model 3's extra times
    t = ds["time"].values
    sel = (t > 1.0) & (t < 1.2)
    q2 = ds["outlet_flux"].sel(model="2").values[sel]
    exact = FLUX_AMPLITUDE * np.sin(t[sel]) * 1.1
    np.testing.assert_allclose(q2, exact, rtol=1e-4)
    mid = FLUX_AMPLITUDE * 1.1 * 0.5 * (np.sin(1.0) + np.sin(1.01))
    np.testing.assert_allclose(ds["outlet_flux"].sel(model="2", time=1.005).item(), mid, rtol=1e-12)
    np.testing.assert_allclose(ds["outlet_flux"].sel(model="3").values, FLUX_AMPLITUDE * np.sin(t) * 1.15,
                               rtol=1e-12)
    # stent-only variables: NaN for model 1
    for v in ("stent_max_von_mises", "hole_flux", "stent_von_mises_line", "hole_velocity_y"):
        assert np.isnan(ds[v].sel(model="1").values).all(), v
        assert np.isfinite(ds[v].sel(model="3").values).any(), v
    # holes padded to the largest count, positions per model
    assert ds.sizes["hole"] == 11
    assert np.isfinite(ds["hole_z"].sel(model="4").values).sum() == 3
    assert ds["outlet_hole_z"].sel(model="3").item() == pytest.approx(0.04875)
    assert ds.attrs["run_3_symmetry"] == "quarter" and ds.attrs["run_1_symmetry"] == "axisymmetric"
    assert "run_2_config_hash" in ds.attrs and "run_2_wall_time_s" in ds.attrs
    scenes = json.loads(ds.attrs["scenes"])
    assert scenes["fig04_outlet_flow"] == {k: cfg["scenes"]["fig04_outlet_flow"][k]
                                           for k in ("quantities", "tolerance", "measured_error")}
    out = tmp_path / "models_coarse.nc"
    aggregate.write_dataset(ds, out)
    back = xr.open_dataset(out, decode_times=False)
    assert back["model_label"].values.tolist() == ["No stent", "5 mm", "10 mm", "25 mm"]
    back.close()


def test_combine_models_nominal_grid_and_errors(runs, cfg):
    ds = aggregate.combine_models(runs, cfg, time_grid="nominal")
    assert ds.sizes["time"] == 301 and np.isnan(ds["outlet_flux"].isel(time=0)).all()   # runs start at dt
    with pytest.raises(ValueError, match="two runs"):
        aggregate.combine_models(runs + runs[:1], cfg)


def test_combine_levels(level_runs, cfg, tmp_path):
    ds = aggregate.combine_levels(level_runs, 1.5, cfg)
    assert list(ds["level"].values) == list(cfg["mesh"]["levels"])
    assert ds["stent_von_mises_line"].dims == ("level", "z")
    assert ds["cells"].values.tolist() == [60000, 140000, 320000]
    _check_cf(ds)
    expected = VM_BASE * (1 + 0.1) * (1 + 0.3 * np.exp(-0.5 * ((ds["z"].values - 0.03) / 5e-3) ** 2))
    np.testing.assert_allclose(ds["stent_von_mises_line"].sel(level="coarse").values, expected, rtol=1e-12)
    assert ds["line_max_difference_to_finest"].sel(level="fine").item() == 0.0
    # peak over [0, 1.5 s], the window every level covers: A (1 + 0.05 k) max sin t = A 1.15 sin 1.5
    assert ds["peak_outlet_flux"].sel(level="fine").item() == pytest.approx(FLUX_AMPLITUDE * 1.15 * np.sin(1.5), rel=1e-9)
    # the outlet-most hole (z = 48.75 mm, +y): |1e-10 sin(2 pi (t - z/0.02) / 3)| peaks at t = 3 + 0.75 - 2.4375 s
    # = 1.3125 s inside [0, 1.5 s]; |v_y| = 3e-3 (1 + 1.5) at the hole centre at 1.5 s
    assert ds["peak_outlet_hole_flux"].sel(level="fine").item() == pytest.approx(1e-10, rel=1e-3)
    assert ds["outlet_hole_peak_velocity"].sel(level="fine").item() == pytest.approx(3e-3 * 2.5, rel=1e-12)
    with pytest.raises(ValueError, match="no probe"):
        aggregate.combine_levels(level_runs, 0.7, cfg)
    aggregate.write_dataset(ds, tmp_path / "conv.nc")
    assert (tmp_path / "conv.nc").stat().st_size > 0


def _legend_texts(fig):
    out = []
    for ax in fig.axes:
        if ax.get_legend():
            out += [t.get_text() for t in ax.get_legend().get_texts()]
    out += [t.get_text() for leg in fig.legends for t in leg.get_texts()]
    return out


def _saved(fig, tmp_path, stem):
    paths = figure_paths(tmp_path / "fig" / stem, ["png", "pdf"])
    save_figure(fig, paths, dpi=60)
    for p in paths:
        assert p and __import__("os").path.getsize(p) > 0
    assert not [p for p in (tmp_path / "fig").iterdir() if p.name.startswith(".")]   # no temp files left


def test_figures_from_models(runs, cfg, tmp_path):
    ds = aggregate.combine_models(runs, cfg)
    fig = plotting.fig04_outlet_flow(ds)
    assert fig.axes[0].get_ylabel().endswith("(mm/s)") and fig.axes[1].get_ylabel() == "outlet flow rate (mm³/s)"
    assert _legend_texts(fig) == ["No stent", "5 mm", "10 mm", "25 mm"]
    # plotted in scaled units
    np.testing.assert_allclose(fig.axes[1].lines[1].get_ydata(), ds["outlet_flux"].sel(model="2") * 1e9)
    _saved(fig, tmp_path, "fig04")

    fig = plotting.fig05_wall_displacement(ds)
    assert [ax.get_title() for ax in fig.axes] == ["t = 0.5 s", "t = 1 s", "t = 2 s", "t = 2.5 s"]
    assert fig.axes[0].get_ylabel() == "radial wall\ndisplacement (mm)"
    assert "No stent" in _legend_texts(fig) and "pulse centre" in _legend_texts(fig)
    _saved(fig, tmp_path, "fig05")

    for stem, t in {"fig06": 0.5, "fig07": 1.0, "fig08": 2.0, "fig09": 2.5}.items():
        fig = plotting.fig_hole_velocity(ds, t)
        assert _legend_texts(fig) == ["5 mm", "10 mm", "25 mm"]
        assert fig.axes[0].get_xlabel() == "axial distance from the hole centre (mm)"
        assert fig.axes[0].get_ylabel() == "y-velocity (mm/s)"
        _saved(fig, tmp_path, stem)

    fig = plotting.fig10_stent_von_mises(ds)
    assert _legend_texts(fig) == ["5 mm", "10 mm", "25 mm"]
    assert fig.axes[0].get_ylabel() == "maximum von Mises stress (kPa)"
    _saved(fig, tmp_path, "fig10")

    fig = plotting.fig_hole_flux(ds)
    assert [ax.get_title(loc="left").split(" (")[0] for ax in fig.axes[:3]] == ["5 mm", "10 mm", "25 mm"]
    assert fig.axes[0].get_ylabel() == "hole flux (mm³/s)"
    assert len(fig.axes[0].lines) == 11 + 1
    _saved(fig, tmp_path, "fig11")


def test_figure_convergence(level_runs, cfg, tmp_path):
    conv = aggregate.combine_levels(level_runs, 1.5, cfg)
    fig = plotting.fig03_mesh_convergence(conv)
    assert _legend_texts(fig) == ["coarse (60 000 elements)", "medium (140 000 elements)", "fine (320 000 elements)"]
    assert fig.axes[0].get_ylabel() == "von Mises stress (kPa)"
    _saved(fig, tmp_path, "fig03")


def _tiny_mesh(cfg, tmp_path, symmetry):
    from ureterfsi.mesh.build import build_mesh

    c = copy.deepcopy(cfg)
    c["geometry"]["length"] = 0.01
    c["models"]["3"]["holes"] = 4   # pairs at 1.25 mm and 8.75 mm of a 10 mm segment
    c["mesh"]["sizes"] = {"hole": 2.5e-4, "stent_wall": 5e-4, "ureter_wall": 1e-3, "fluid_bulk": 2e-3}
    c["mesh"]["optimize"] = False
    msh, js = tmp_path / f"m3_{symmetry}.msh", tmp_path / f"m3_{symmetry}.json"
    build_mesh(c, "3", "coarse", symmetry, msh, js)
    return msh, json.loads(js.read_text())


@pytest.mark.parametrize("symmetry", ["quarter", "full"])
def test_figure_domain(cfg, tmp_path, symmetry):
    msh, info = _tiny_mesh(cfg, tmp_path, symmetry)
    fig = plotting.fig02_domain(msh, hole_z=max(info["hole_pair_z"]))
    ax, axz = fig.axes[:2]
    assert ax.get_xlabel() == "z (mm)" and ax.get_ylabel() == "y (mm)"
    assert _legend_texts(fig) == ["Urine", "Ureter", "Stent"]
    faces = ax.collections[0].get_facecolors()
    # every region is present among the drawn facets
    for t in (1, 2, 3):
        rgba = matplotlib.colors.to_rgba(plotting.REGION_COLORS[t])
        assert np.isclose(faces, rgba).all(axis=1).any(), t
    assert "outlet-most" in axz.get_title()
    _saved(fig, tmp_path, f"fig02_{symmetry}")


def test_facet_regions_hole_channel_is_fluid(cfg, tmp_path):
    """In the mirror plane x = 0 the hole channels (stent radii, near a hole centre) are urine."""
    msh, info = _tiny_mesh(cfg, tmp_path, "quarter")
    m = read_msh(msh)
    coords, cells, sym = m.coords, m.cells(), m.elements(2, tags.SYMMETRY_X)
    reg = plotting._facet_regions(cells, sym)
    assert (reg > 0).all()
    c = coords[sym].mean(axis=1)
    g = UreterGeometry.from_config(cfg)
    in_wall = (c[:, 1] > g.stent_inner_radius) & (c[:, 1] < g.stent_outer_radius)
    near_hole = np.abs(c[:, 2] - 0.00875) < 0.5 * g.hole_radius
    far = np.abs(c[:, 2] - 0.005) < 1e-3
    assert (reg[in_wall & near_hole] == 1).all() and (reg[in_wall & near_hole] == 1).any()
    assert (reg[in_wall & far] == 3).all()


def test_table1(cfg, tmp_path):
    sidecars = []
    for m in cfg["models"]:
        p = tmp_path / f"model{m}.json"
        sm = StentModel.from_config(cfg, m)
        z = hole_pair_positions(UreterGeometry.from_config(cfg), sm).tolist()
        p.write_text(json.dumps({"model": m, "level": "coarse", "symmetry": "quarter", "cells_total": 1000 * int(m),
                                 "cells": {"fluid": 500, "ureter": 400} | ({"stent": 100} if sm.stent else {}),
                                 "hole_pair_z": z, "hole_channels_found": len(z),
                                 FORMAT_VERSION_ATTR: FORMAT_VERSION}))
        sidecars.append(p)
    rows = plotting.table1(cfg, sidecars)
    assert [r["label"] for r in rows] == ["No stent", "5 mm", "10 mm", "25 mm"]
    assert [r["side_holes"] for r in rows] == [0, 22, 12, 6]
    assert rows[2]["hole_pairs_z_mm"] == "1.25 10 20 30 40 48.75"
    assert rows[0]["elements_stent"] == 0
    plotting.write_table1(rows, tmp_path / "t.csv", tmp_path / "t.md")
    assert (tmp_path / "t.csv").read_text().splitlines()[0].startswith("model,label,hole_pair_spacing_mm")
    md = (tmp_path / "t.md").read_text().splitlines()
    assert len(md) == 6 and "| 3 | 10 mm | 10 | 12 |" in md[4]


def test_workflow_rules_dry_run(tmp_path, cfg, repo_root):
    """The aggregate and figure rules wire up (run files present, meshes to be built): dry run of all_figures."""
    import subprocess

    st = cfg["study"]

    def run_path(m, lv):   # results/runs/{fidelity}/{symmetry}/model{m}_{level}.nc (study.fidelity, study.runs)
        over = st["runs"].get(m, {})
        path = tmp_path / "results" / "runs" / over.get("fidelity", st["fidelity"]) / \
            over.get("symmetry", cfg["mesh"]["symmetry"]) / f"model{m}_{lv}.nc"
        path.parent.mkdir(parents=True, exist_ok=True)
        return path

    for m in cfg["models"]:
        synthetic_run(cfg, m, end=0.05).to_netcdf(run_path(m, st["level"]))
    for lv in cfg["mesh"]["levels"]:
        if lv != st["level"]:
            synthetic_run(cfg, st["convergence_model"], level=lv, end=0.05).to_netcdf(
                run_path(st["convergence_model"], lv))
    rules = repo_root / "workflow" / "rules"
    (tmp_path / "Snakefile").write_text(
        f'configfile: "{repo_root}/config/config.yaml"\n'
        + "".join(f'include: "{rules / f}"\n' for f in ("common.smk", "mesh.smk", "aggregate.smk", "figures.smk")))
    run = subprocess.run([sys.executable, "-m", "snakemake", "-n", "--cores", "1", "all_figures"], cwd=tmp_path,
                         capture_output=True, text=True, timeout=300)
    assert run.returncode == 0, run.stderr[-3000:]
    for rule in ("aggregate_models", "aggregate_convergence", "fig02_domain", "fig03_mesh_convergence",
                 "fig04_outlet_flow", "fig05_wall_displacement", "fig06_hole_velocity", "fig09_hole_velocity",
                 "fig10_stent_von_mises", "fig11_hole_flux", "table1"):
        assert f"rule {rule}:" in run.stdout, rule
