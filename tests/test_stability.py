"""Stability at the extremes (issue 5): the CI subset of the stability matrix (ureterfsi.stability).

Short runs of the stent-free r-z model (the whole 50 mm segment, coarse mesh, ~12k unknowns): the baseline,
the largest time step of the matrix, and an absurd load (40 x the paper's) that inverts the ALE mesh within
a few steps, whose diagnosis must name the limit, the time and the place. The whole matrix is the workflow
target `stability` (results/datasets/stability.nc, results/figures/stability_map.png).
"""
from __future__ import annotations

import math

import numpy as np
import pytest
import xarray as xr

from ureterfsi import stability as S
from ureterfsi.mesh import build_mesh


@pytest.fixture(scope="module")
def rz_mesh(tmp_path_factory, _default_cfg):
    tmp = tmp_path_factory.mktemp("stability")
    msh = tmp / "model1_coarse.msh"
    build_mesh(_default_cfg, "1", "coarse", "axisymmetric", msh, tmp / "model1_coarse.json")
    return msh


@pytest.fixture(scope="module")
def runs(_default_cfg, rz_mesh):
    cfg = _default_cfg
    return {
        "baseline": S.run_case(cfg, S.Case("baseline"), mesh_path=rz_mesh, end=0.2),
        "dt": S.run_case(cfg, S.Case("time_step", 0.1), mesh_path=rz_mesh, end=0.3),
        "absurd_load": S.run_case(cfg, S.Case("load_amplitude", 2.0e6), mesh_path=rz_mesh, end=0.3),
    }


def test_cases_follow_the_configuration(cfg):
    cases = S.cases(cfg)
    names = [c.name for c in cases]
    assert names[0] == "baseline" and len(names) == len(set(names))
    assert {"time_step_0.001", "time_step_0.1", "mesh_level_fine", "bulk_ratio_1e6", "density_ratio_0.01",
            "load_amplitude_0", "load_amplitude_2e5", "wave_speed_0.01", "viscosity_0.00013"} <= set(names)
    u = cfg["ureter"]
    s = S.case_setup(cfg, S.case_by_name(cfg, "bulk_ratio_10"))
    assert s["cfg"]["ureter"]["bulk_modulus"] == pytest.approx(10 * (u["c10"] + u["c01"]))
    assert cfg["ureter"]["bulk_modulus"] == 1.0e9                   # the configuration itself is untouched
    s = S.case_setup(cfg, S.case_by_name(cfg, "density_ratio_100"))
    assert s["cfg"]["ureter"]["density"] == pytest.approx(100 * cfg["fluid"]["density"])
    s = S.case_setup(cfg, S.case_by_name(cfg, "wave_speed_0.01"))   # same travel distance as the baseline
    assert s["end"] == pytest.approx(2 * cfg["stability"]["end"])
    assert S.case_setup(cfg, S.case_by_name(cfg, "mesh_level_fine"))["level"] == "fine"
    cfg["mesh"]["levels"].pop("fine")
    with pytest.raises(ValueError, match="mesh level 'fine' is not one of mesh.levels"):
        S.case_setup(cfg, S.Case("mesh_level", "fine"))


def test_baseline_is_stable_with_bounded_energy_and_conserved_volume(runs):
    ds = runs["baseline"]
    assert ds["outcome"].item() == "stable" and ds["limit"].item() == "none" and ds["diagnosis"].item() == ""
    assert ds["reached_time"].item() == pytest.approx(0.2)
    e = ds["kinetic_energy"].values
    assert np.all(np.isfinite(e)) and e.max() > 1e-9              # J: the wave moves urine and wall
    assert np.all(e <= ds["energy_bound"].values)                  # physically bounded (safety factor unused)
    # measured 6.7e-4 over 0.3 s (O(dt^2) geometric-conservation defect of BDF on the moving mesh)
    assert ds["displaced_volume"].item() > 1e-8                     # m^3
    assert ds["volume_error"].item() < 2e-3
    assert ds["min_jacobian"].item() > 0.9
    assert ds["step_halvings"].item() == 0 and ds["mean_newton_iterations"].item() >= 1
    for name in ds.variables:
        assert {"units", "long_name"} <= set(ds[name].attrs), name
    for key in ("config_hash", "git_commit", "version_dolfinx", "case", "energy_safety"):
        assert key in ds.attrs


def test_largest_time_step_runs_with_bounded_energy(runs):
    """dt = 0.1 s: the pulse moves 2 mm (4 wall elements) per step and the first step spans the whole ramp."""
    ds = runs["dt"]
    assert ds["steps"].item() == 3 and ds["reached_time"].item() == pytest.approx(0.3)
    assert ds["max_energy_ratio"].item() < 1.0
    assert ds["min_jacobian"].item() > 0.9
    # stable, or stopped only by the (accuracy) volume limit, which names itself
    assert ds["outcome"].item() == "stable" or ds["limit"].item() == "volume", ds["diagnosis"].item()


def test_absurd_load_fails_with_a_diagnosis_naming_limit_time_and_place(runs):
    """40 x the paper's load: the wall bulges next to the clamped inlet end and the first fluid cells
    there fold over; the engine stops at the inverted ALE map and the case records where and when."""
    ds = runs["absurd_load"]
    d = ds["diagnosis"].item()
    assert ds["outcome"].item() == "failed" and ds["limit"].item() == "ale_inversion", d
    t = ds["failure_time"].item()
    assert 0.0 < t < 0.3 and ds["min_jacobian"].item() <= 0.0
    assert d.startswith("ale_inversion: ALE mesh inverted at t=")
    assert f"t={t:.6g} s" in d                                           # when
    assert "(r, z) = (" in d and "mm" in d and "pulse centre" in d       # where
    r, z = ds["failure_r"].item(), ds["failure_z"].item()
    assert abs(r - 4e-3) < 0.6e-3 and z < 3e-3                          # at the wall, next to the clamped inlet
    assert ds["steps"].item() >= 1 and np.isfinite(ds["kinetic_energy"].values).all()


def test_a_broken_case_is_recorded_not_raised(cfg, rz_mesh):
    cfg["solver"]["mesh_motion"] = "laplace"        # refused by the engine while it builds the problem
    ds = S.run_case(cfg, S.Case("baseline"), mesh_path=rz_mesh, end=0.02)
    assert ds["outcome"].item() == "failed" and ds["limit"].item() == "exception"
    assert ds["diagnosis"].item().startswith("exception: ValueError: mesh motion: 'harmonic' or 'elastic'")
    assert ds["steps"].item() == 0 and math.isnan(ds["max_kinetic_energy"].item())


def test_matrix_dataset_and_stability_map(runs, tmp_path):
    from ureterfsi.plotting import save_figure, stability_map

    paths = []
    for name, ds in runs.items():
        paths.append(tmp_path / f"{name}.nc")
        S.write_case(ds, paths[-1])
    m = S.combine(paths, {"stability": {}})
    assert list(m["case"].values) == ["baseline", "time_step_0.1", "load_amplitude_2e6"]
    assert m["kinetic_energy"].dims == ("case", "step") and m.sizes["step"] == 21
    assert list(m["outcome"].values)[2] == "failed" and m["axis"].values[1] == "time_step"
    for name in m.variables:
        assert {"units", "long_name"} <= set(m[name].attrs), name
    assert "config_hash" in m.attrs and "case_baseline_git_commit" in m.attrs
    S.write_case(m, tmp_path / "stability.nc")
    with xr.open_dataset(tmp_path / "stability.nc") as back:
        assert str(back["diagnosis"].values[2]).startswith("ale_inversion")
    table = S.outcome_table(m)
    assert table.count("\n") == 4 and "ale_inversion" in table
    png = tmp_path / "stability_map.png"
    save_figure(stability_map(m), [png], dpi=60)
    assert png.stat().st_size > 10_000
