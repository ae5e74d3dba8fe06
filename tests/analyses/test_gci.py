"""Grid Convergence Index (ureterfsi.analyses.gci): the worked example of Celik et al. 2008 (Table 1), exact power
laws, oscillatory / divergent / identical data, the GCI dataset of a mesh-convergence dataset, and the
workflow script of rules `gci` and `table_gci`."""
from __future__ import annotations

import json
import math
import runpy
import subprocess
import sys
import time
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest
import xarray as xr

from ureterfsi.analyses import aggregate
from ureterfsi.data.checked import open_netcdf
from ureterfsi.data.provenance import FORMAT_VERSION
from ureterfsi.analyses.gci import (GCI_DATASET, DEFAULT_POINTS_Z, gci_dataset, mesh_measure, representative_cell_size,
                           three_grid_gci, extrapolated_values, quantity_values,
                           write_gci_table)
from helpers.synthetic import P_FLUX, P_LINE, P_VM, convergence_dataset

REPO = Path(__file__).resolve().parents[2]


# --------------------------------------------------------------------------- Celik et al. 2008, Table 1
def _celik(n, phi):
    return three_grid_gci(representative_cell_size(n, 1.0, dim=2), phi)


def test_celik_table1_monotone_reattachment_length():
    """Column 1 (2D, dimensionless reattachment length): published r21 = 1.5, r32 = 1.333, p = 1.53,
    phi_ext21 = 6.1685, e_a21 = 1.5 %, e_ext21 = 1.7 %, GCI_fine21 = 2.04 %."""
    r = _celik([18000, 8000, 4500], [6.063, 5.972, 5.863])
    assert r.diagnosis == "monotone" and r.note == ""
    assert r.r21 == pytest.approx(1.5, abs=1e-12) and round(r.r32, 3) == 1.333
    assert round(r.apparent_order, 2) == 1.53
    assert round(r.phi_ext21, 4) == 6.1685
    assert round(100 * r.e_a21, 1) == 1.5 and round(100 * r.e_ext21, 1) == 1.7
    # The published GCI_fine21 = 2.04 % is not what the paper's own Eq. gives with its own p and phi_ext:
    # Fs e_a21/(r21^p - 1) = Fs (phi_ext21 - phi1)/phi1 = 1.25 * 0.1055 / 6.063 = 2.175 %.
    assert r.gci_fine21 == pytest.approx(1.25 * (6.1685 - 6.063) / 6.063, rel=2e-4)
    assert 100 * r.gci_fine21 == pytest.approx(2.175, abs=5e-4)
    assert 0 < r.convergence_ratio < 1 and r.asymptotic_ratio == pytest.approx(1.0, abs=0.05)


def test_celik_table1_low_order_column():
    """Column 2 (N = 18000 / 4500 / 980): published r21 = 2, r32 = 2.143, p = 0.75, phi_ext21 = 10.8801,
    e_a21 = 0.6 %, GCI_fine21 = 1.1 %."""
    r = _celik([18000, 4500, 980], [10.7880, 10.7250, 10.6050])
    assert r.diagnosis == "monotone"
    assert r.r21 == pytest.approx(2.0) and round(r.r32, 3) == 2.143
    assert round(r.apparent_order, 2) == 0.75
    assert round(r.phi_ext21, 4) == 10.8801
    assert round(100 * r.e_a21, 1) == 0.6 and round(100 * r.gci_fine21, 1) == 1.1
    assert r.e_ext21 == pytest.approx(abs((r.phi_ext21 - 10.788) / r.phi_ext21), rel=1e-12)


def test_celik_table1_oscillatory_column():
    """Column 3 (oscillatory convergence): published p = 1.51, phi_ext21 = 6.0269, e_a21 = 0.7 %,
    e_ext21 = 0.38 %, GCI_fine21 = 0.47 %."""
    r = _celik([18000, 4500, 980], [6.0042, 5.9624, 6.0909])
    assert r.diagnosis == "oscillatory" and r.convergence_ratio < 0 and "oscillatory" in r.note
    assert round(r.apparent_order, 2) == 1.51
    assert round(r.phi_ext21, 4) == 6.0269
    assert round(100 * r.e_a21, 1) == 0.7 and round(100 * r.e_ext21, 2) == 0.38
    assert round(100 * r.gci_fine21, 2) == 0.47


# ------------------------------------------------------------------------------------ exact power laws
@pytest.mark.parametrize("p_true", [0.8, 1.7, 2.0, 3.0])
@pytest.mark.parametrize("h", [(1.0, 1.3, 2.1), (0.5, 1.0, 2.0), (1.0, 1.5, 1.8)])
def test_exact_power_law_recovered(h, p_true):
    """phi(h) = phi0 + C h^p exactly: p and phi0 to round-off, any input order."""
    h = np.asarray(h)
    phi0, C = 3.0, -0.7
    phi = phi0 + C * h ** p_true
    perm = [2, 0, 1]
    r = three_grid_gci(h[perm], phi[perm])
    assert r.diagnosis == "monotone"
    assert r.h == tuple(sorted(h)) and r.order == (1, 2, 0)
    assert r.apparent_order == pytest.approx(p_true, abs=1e-10)
    assert r.phi_ext21 == pytest.approx(phi0, abs=1e-12) and r.phi_ext32 == pytest.approx(phi0, abs=1e-12)
    assert r.e_ext21 == pytest.approx(abs(C * h.min() ** p_true / phi0), rel=1e-8)
    assert r.gci_fine21 == pytest.approx(1.25 * r.e_ext21 * abs(phi0 / phi[np.argmin(h)]), rel=1e-8)


def test_representative_cell_size():
    assert representative_cell_size(1000, 8.0, 3) == pytest.approx(0.2)
    np.testing.assert_allclose(representative_cell_size([100, 400], 1.0, 2), [0.1, 0.05])
    for bad in ([0, 10], [-1], [np.nan]):
        with pytest.raises(ValueError):
            representative_cell_size(bad)


# ----------------------------------------------------------------------- non-monotone and degenerate data
def test_oscillatory_manufactured():
    r = three_grid_gci([1.0, 2.0, 4.0], [1.0, 0.99, 1.03])     # eps21 = -0.01, eps32 = +0.04
    assert r.diagnosis == "oscillatory" and r.convergence_ratio == pytest.approx(-0.25)
    assert r.apparent_order == pytest.approx(2.0, abs=1e-12)    # r21 = r32: p = ln|eps32/eps21| / ln r
    assert math.isfinite(r.gci_fine21) and r.gci_fine21 > 0


def test_divergent():
    r = three_grid_gci([1.0, 2.0, 3.0], [1.0, 1.1, 1.15])       # differences grow with refinement
    assert r.diagnosis == "divergent" and r.convergence_ratio == pytest.approx(2.0)
    assert math.isnan(r.apparent_order) and math.isnan(r.phi_ext21) and math.isnan(r.gci_fine21)
    assert r.e_a21 == pytest.approx(0.1) and "grows" in r.note
    r = three_grid_gci([1.0, 2.0, 3.0], [1.0, 1.1, 1.1])        # coarse pair identical, fine pair not
    assert r.diagnosis == "divergent" and math.isnan(r.gci_fine21)


def test_divergence_bound_for_unequal_ratios():
    """R = eps21/eps32 is compared with ln r21/ln r32 (1 for a constant ratio), not with 1."""
    h = np.array([1.0, 1.5, 1.8])
    r = three_grid_gci(h, 1.0 + h ** 2)                         # exact, p = 2, but R = 1.25/0.99 > 1
    assert r.convergence_ratio == pytest.approx(1.25 / 0.99) and r.diagnosis == "monotone"
    assert r.apparent_order == pytest.approx(2.0, abs=1e-10) and r.phi_ext21 == pytest.approx(1.0, abs=1e-12)
    r = three_grid_gci([1.0, 1.1, 4.4], [1.0, 1.01, 1.03])      # R = 0.5 < 1, but ln 1.1/ln 4 = 0.069
    assert r.convergence_ratio == pytest.approx(0.5) and r.diagnosis == "divergent"
    assert math.isnan(r.apparent_order) and math.isnan(r.gci_fine21) and "ln r21/ln r32" in r.note


def test_identical_and_indeterminate():
    r = three_grid_gci([1.0, 2.0, 3.0], [5.0, 5.0, 5.0])
    assert r.diagnosis == "identical" and math.isnan(r.apparent_order)
    assert r.phi_ext21 == 5.0 and r.e_a21 == 0.0 and r.gci_fine21 == 0.0 and r.gci32 == 0.0
    r = three_grid_gci([1.0, 2.0, 3.0], [5.0, 5.0, 6.0])
    assert r.diagnosis == "indeterminate" and math.isnan(r.apparent_order) and math.isnan(r.gci_fine21)
    r = three_grid_gci([1.0, 2.0, 3.0], [0.0, 0.0, 0.0])        # relative errors of a zero value: NaN
    assert r.diagnosis == "identical" and math.isnan(r.gci_fine21)


def test_non_convergent_iteration_gives_nan():
    """Very different ratios (r21 = 1.1, r32 = 4) with s = -1: the fixed-point map is not a contraction."""
    r = three_grid_gci([1.0, 1.1, 4.4], [1.0, 1.01, 0.9])
    assert r.diagnosis == "oscillatory" and math.isnan(r.apparent_order)
    assert math.isnan(r.phi_ext21) and math.isnan(r.gci_fine21) and "did not converge" in r.note
    assert r.e_a21 == pytest.approx(0.01)


def test_malformed_input_raises():
    with pytest.raises(ValueError, match="three grids"):
        three_grid_gci([1.0, 2.0], [1.0, 2.0])
    with pytest.raises(ValueError, match="differ"):
        three_grid_gci([1.0, 1.0, 2.0], [1.0, 2.0, 3.0])
    with pytest.raises(ValueError, match="finite"):
        three_grid_gci([1.0, 2.0, 3.0], [1.0, np.nan, 3.0])


# ------------------------------------------------------------------------------------------- datasets
def _check_cf(ds):
    for name, var in ds.variables.items():
        assert "units" in var.attrs and "long_name" in var.attrs, name


def test_gci_dataset_recovers_power_laws(tmp_path):
    conv, f, z = convergence_dataset()
    ds = gci_dataset(conv)
    names = ["peak_outlet_flux", "peak_stent_max_von_mises", "stent_von_mises_z12_5mm", "stent_von_mises_z25mm",
             "stent_von_mises_z37_5mm"]
    assert list(ds["quantity"].values) == names
    assert all(quantity_values(ds, q).dims == ("level",) for q in names)
    assert list(ds["level"].values) == ["coarse", "medium", "fine"]
    assert ds.attrs["fine_level"] == "fine" and ds.attrs["coarse_level"] == "coarse"
    np.testing.assert_allclose(ds["r21"], (320000 / 140000) ** (1 / 3), rtol=1e-12)
    np.testing.assert_allclose(ds["r32"], (140000 / 60000) ** (1 / 3), rtol=1e-12)
    np.testing.assert_allclose(ds["h"], ds["cells"] ** (-1 / 3), rtol=1e-12)
    np.testing.assert_allclose(ds["apparent_order"], [P_FLUX, P_VM, P_LINE, P_LINE, P_LINE], rtol=1e-8)
    fz = np.interp(DEFAULT_POINTS_Z, z, f)
    np.testing.assert_allclose(extrapolated_values(ds), [1e-8, 6e3, *fz], rtol=1e-10)
    np.testing.assert_allclose(ds["probe_z"][2:], DEFAULT_POINTS_Z)
    assert np.isnan(ds["probe_z"][:2]).all()
    assert list(ds["diagnosis"].values) == ["monotone"] * 5
    assert [quantity_values(ds, q).attrs["units"] for q in names] == ["m3 s-1", "Pa", "Pa", "Pa", "Pa"]
    assert [ds[f"extrapolated_value_{q}"].attrs["units"] for q in names] == ["m3 s-1", "Pa", "Pa", "Pa", "Pa"]
    assert (ds["gci_fine21"] > 0).all() and (ds["gci32"] > ds["gci_fine21"]).all()
    _check_cf(ds)
    # provenance: the input's attrs are kept, its own provenance under input_*
    assert ds.attrs["model"] == "3" and ds.attrs["run_fine_cells"] == 320000 and ds.attrs["probe_time"] == 1.5
    assert ds.attrs["input_config_hash"] == "abc" and ds.attrs["input_git_commit"] == "deadbeef"
    assert {"config_hash", "git_commit", "created", "version_numpy"} <= set(ds.attrs)
    assert ds.attrs["Conventions"] == "CF-1.8" and "Celik" in ds.attrs["references"]
    assert ds.attrs["safety_factor"] == 1.25
    # netCDF round trip (atomic write of the workflow)
    aggregate.write_dataset(ds, tmp_path / "gci.nc")
    back = open_netcdf(tmp_path / "gci.nc", GCI_DATASET)
    assert list(back["diagnosis"].values) == ["monotone"] * 5
    np.testing.assert_allclose(back["apparent_order"], ds["apparent_order"])


def test_gci_dataset_options_and_diagnoses():
    conv, f, z = convergence_dataset(flux_sign=1.0)
    conv["peak_outlet_flux"][:] = 2e-8                      # identical on every level
    conv["peak_stent_max_von_mises"][:] = [6.0e3, 6.2e3, 6.1e3]   # oscillatory
    ds = gci_dataset(conv, points_z=[0.01], measure=2e-6, dim=3)
    assert list(ds["quantity"].values) == ["peak_outlet_flux", "peak_stent_max_von_mises", "stent_von_mises_z10mm"]
    assert list(ds["diagnosis"].values) == ["identical", "oscillatory", "monotone"]
    assert ds["gci_fine21"].values[0] == 0.0
    assert ds["h"].attrs["units"] == "m"
    np.testing.assert_allclose(ds["h"], (2e-6 / ds["cells"]) ** (1 / 3))
    np.testing.assert_allclose(ds["apparent_order"][2], P_LINE, rtol=1e-8)    # h scale does not change p
    with pytest.raises(ValueError, match="outside the probe line"):
        gci_dataset(conv, points_z=[0.06])


def test_gci_dataset_needs_three_levels():
    conv, _, _ = convergence_dataset()
    with pytest.raises(ValueError, match="three mesh levels.*has 2"):
        gci_dataset(conv.isel(level=[0, 2]))


def test_gci_dataset_uses_three_finest_of_four():
    conv, f, z = convergence_dataset()
    extra, _, _ = convergence_dataset(cells=(20000, 60000, 140000), levels=("xcoarse", "coarse", "medium"))
    four = xr.concat([extra.isel(level=[0]), conv], dim="level")
    ds = gci_dataset(four)
    assert ds.sizes["level"] == 4 and ds.attrs["gci_levels"] == "fine,medium,coarse"
    np.testing.assert_allclose(ds["apparent_order"][2:], P_LINE, rtol=1e-8)


def test_gci_dataset_from_combine_levels(cfg, tmp_path):
    """The real layout: run files -> aggregate.combine_levels -> gci_dataset (synthetic runs of
    tests/analyses/test_aggregate_figures.py, whose peaks do not depend on the level: diagnosis 'identical')."""
    from helpers.synthetic import VM_BASE, synthetic_run

    cells = (60000, 140000, 320000)
    paths = []
    for lv, n in zip(cfg["mesh"]["levels"], cells):
        factor = 1.0 + 40.0 * n ** (-2.0 / 3.0)               # line = base (1 + 40 h^2), h = N^(-1/3)
        p = tmp_path / f"model3_{lv}.nc"
        synthetic_run(cfg, "3", level=lv, end=1.6, level_factor=factor, cells=n).to_netcdf(p)
        paths.append(p)
    conv = aggregate.combine_levels(paths, 1.5, cfg)
    ds = gci_dataset(conv, cfg=cfg)
    # the scalars (outlet flux, stent maximum, the outlet-most hole's flux and velocity), then the line points
    assert list(ds["quantity"].values[:4]) == ["peak_outlet_flux", "peak_stent_max_von_mises",
                                               "peak_outlet_hole_flux", "outlet_hole_peak_velocity"]
    assert list(ds["diagnosis"].values) == ["identical"] * 4 + ["monotone"] * 3
    np.testing.assert_allclose(ds["apparent_order"][4:], 2.0, rtol=1e-6)
    line_z = conv["z"].values      # the synthetic line at t = 1.5 s is VM_BASE (1 + 0.3 exp(...)) x factor
    exact = np.interp(DEFAULT_POINTS_Z, line_z, VM_BASE * (1 + 0.3 * np.exp(-0.5 * ((line_z - 0.03) / 5e-3) ** 2)))
    np.testing.assert_allclose(extrapolated_values(ds)[4:], exact, rtol=1e-8)
    assert ds.attrs["model"] == "3" and "run_fine_cells" in ds.attrs


def test_gci_table(tmp_path):
    conv, _, _ = convergence_dataset()
    ds = gci_dataset(conv)
    rows = write_gci_table(ds, tmp_path / "t.csv", tmp_path / "t.md")
    assert len(rows) == 5
    head = (tmp_path / "t.csv").read_text().splitlines()[0].split(",")
    assert head[:5] == ["quantity", "units", "phi1_fine", "phi2_medium", "phi3_coarse"] and "gci_fine21" in head
    md = (tmp_path / "t.md").read_text()
    assert "| stent von Mises stress at z = 25 mm | kPa |" in md and "mm³/s" in md and "monotone" in md
    assert "Cells: fine 320000, medium 140000, coarse 60000" in md


def test_mesh_measure(tmp_path):
    p = tmp_path / "m.json"
    p.write_text(json.dumps({"ureterfsi_format_version": FORMAT_VERSION, "measure": "volume", "subdomain_measure": {
        "fluid": {"analytic": 1e-6, "mesh": 0.99e-6}, "stent": {"analytic": 2e-7, "mesh": 2e-7}}}))
    vol, dim = mesh_measure(p)
    assert vol == pytest.approx(1.2e-6) and dim == 3


# ------------------------------------------------------------------------------------------- workflow
def test_workflow_script(tmp_path):
    """workflow/scripts/gci.py for both rules, with a stand-in for Snakemake's `snakemake` object."""
    conv, _, _ = convergence_dataset()
    conv_path = tmp_path / "mesh_convergence.nc"
    aggregate.write_dataset(conv, conv_path)
    side = tmp_path / "model3_fine.json"
    side.write_text(json.dumps({"ureterfsi_format_version": FORMAT_VERSION, "measure": "volume", "subdomain_measure": {"fluid": {"analytic": 1e-6}}}))
    out, log = tmp_path / "gci.nc", tmp_path / "gci.log"

    class Files(list):
        def __init__(self, items=(), **named):
            super().__init__(list(items) + list(named.values()))
            self.__dict__.update(named)
            self._names = list(named)

        def keys(self):
            return self._names

    smk = SimpleNamespace(rule="gci", input=Files(conv=str(conv_path), mesh=str(side)), output=Files([str(out)]),
                          params=SimpleNamespace(points_z=[0.0125, 0.025, 0.0375], safety_factor=1.25),
                          log=[str(log)], config={})
    script = REPO / "workflow" / "scripts" / "gci.py"
    runpy.run_path(str(script), init_globals={"snakemake": smk})
    ds = open_netcdf(out, GCI_DATASET)
    assert ds.attrs["mesh_measure"] == pytest.approx(1e-6) and ds["h"].attrs["units"] == "m"
    np.testing.assert_allclose(ds["apparent_order"], [P_FLUX, P_VM, P_LINE, P_LINE, P_LINE], rtol=1e-8)
    tab = SimpleNamespace(rule="table_gci", input=Files(gci=str(out)),
                          output=Files(csv=str(tmp_path / "t.csv"), md=str(tmp_path / "t.md")),
                          log=[str(tmp_path / "t.log")], config={})
    runpy.run_path(str(script), init_globals={"snakemake": tab})
    assert (tmp_path / "t.md").read_text().count("monotone") == 5
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".")]     # no temporary files left


def test_workflow_rules_run(tmp_path, cfg, repo_root):
    """Rules gci and table_gci run by Snakemake on a synthetic mesh-convergence dataset (the upstream rules
    excluded with --allowed-rules); all_figures asks for the table with three levels (dry run)."""
    sym, model, last = cfg["mesh"]["symmetry"], cfg["study"]["convergence_model"], list(cfg["mesh"]["levels"])[-1]
    conv, _, _ = convergence_dataset()
    aggregate.write_dataset(conv, tmp_path / "results/datasets/mesh_convergence.nc")
    side = tmp_path / f"results/meshes/{sym}/model{model}_{last}.json"
    side.parent.mkdir(parents=True)
    side.write_text(json.dumps({"ureterfsi_format_version": FORMAT_VERSION, "measure": "volume", "subdomain_measure": {"fluid": {"analytic": 1e-6}}}))
    rules = repo_root / "workflow" / "rules"
    (tmp_path / "Snakefile").write_text(
        f'configfile: "{repo_root}/config/config.yaml"\n'
        + "".join(f'include: "{rules / f}"\n' for f in ("common.smk", "mesh.smk", "aggregate.smk", "figures.smk")))
    t0 = time.perf_counter()
    run = subprocess.run([sys.executable, "-m", "snakemake", "--cores", "1", "--allowed-rules", "gci", "table_gci",
                          "--", "results/figures/table_gci.md"], cwd=tmp_path, capture_output=True, text=True,
                         timeout=300)
    assert run.returncode == 0, run.stderr[-3000:]
    assert time.perf_counter() - t0 < 60
    ds = open_netcdf(tmp_path / "results/datasets/mesh_convergence_gci.nc", GCI_DATASET)
    np.testing.assert_allclose(ds["probe_z"][2:], [0.0125, 0.025, 0.0375])
    assert (tmp_path / "results/figures/table_gci.csv").stat().st_size > 0
    assert (tmp_path / "results/logs/aggregate/mesh_convergence_gci.log").stat().st_size > 0
    # the whole pipeline (repository Snakefile) asks for the GCI table when there are three levels
    dry = subprocess.run([sys.executable, "-m", "snakemake", "--snakefile", str(repo_root / "Snakefile"),
                          "--configfile", str(repo_root / "config" / "config.yaml"), "-n",
                          "--cores", "1", "all_figures"], cwd=tmp_path, capture_output=True, text=True, timeout=300)
    assert dry.returncode == 0, dry.stderr[-3000:]
    assert "rule gci:" in dry.stdout and "rule table_gci:" in dry.stdout
