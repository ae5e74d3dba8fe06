"""Stability at the extremes: the CI subset of the stability matrix (ureterfsi.stability).

Short runs of the stent-free r-z model (the whole 50 mm segment, coarse mesh, ~12k unknowns): the baseline,
the largest time step of the matrix, and an absurd load (40 x the paper's) that inverts the ALE mesh within
a few steps, whose diagnosis must name the limit, the time and the place. The whole matrix is the workflow
target `stability` (results/datasets/stability.nc, results/figures/stability_map.png).
"""
from __future__ import annotations

import math
import subprocess
import sys

import numpy as np
import pytest
import xarray as xr

from ureterfsi import stability as S
from ureterfsi.config import load_config_files, validate_config
from ureterfsi.mesh.build import build_mesh


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


@pytest.fixture(scope="module")
def hole_run(repo_root):
    """The 3D one-way scene on the 10 mm test segment, model 4 (one hole in the quarter), 2 elements across
    the hole, four 10 ms steps through the load ramp (the overlay's 20 ms steps leave a 1.5 % volume
    balance error: O(dt^2) on a 40 ms ramp)."""
    cfg = load_config_files([repo_root / "config/config.yaml", repo_root / "config/segment-10mm.yaml"])
    cfg["time"]["dt"] = 0.01
    return S.run_case(cfg, S.Case("hole_elements", 2.0), end=0.04)


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
    # side holes: a 3D stented model whose hole size is the case's; n = 4 is the study's own coarse mesh
    for n, stent_wall in ((1, 5e-4), (2, 2.5e-4), (3, 2.5e-4), (4, 2.5e-4)):
        s = S.case_setup(cfg, S.case_by_name(cfg, f"hole_elements_{n}"))
        assert (s["scene"], s["model"], s["symmetry"]) == ("holes", "4", "quarter")
        sizes = s["cfg"]["mesh"]["sizes"]
        assert sizes["hole"] == pytest.approx(cfg["geometry"]["hole_diameter"] / n)
        assert sizes["stent_wall"] == pytest.approx(stent_wall)     # never finer than the hole
        validate_config(s["cfg"])                                   # minima lowered with the sizes
        assert s["parameters"]["is_baseline"] == (n == 4)
    assert S.case_setup(cfg, S.Case("baseline"))["parameters"]["is_baseline"] == 1
    assert math.isnan(S.case_setup(cfg, S.Case("baseline"))["parameters"]["hole_elements"])
    cfg["stability"]["holes"]["model"] = "1"
    with pytest.raises(ValueError, match="has no side holes"):
        S.case_setup(cfg, S.Case("hole_elements", 2.0))
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


def test_coarse_hole_case_runs_in_3d_with_bounded_energy_and_conserved_volume(hole_run):
    ds = hole_run
    assert ds["outcome"].item() == "stable", ds["diagnosis"].item()
    assert ds["scene"].item() == "holes" and ds.attrs["symmetry"] == "quarter" and ds.attrs["model"] == "4"
    assert ds["hole_channels_found"].item() == 1 and ds["hole_elements"].item() == 2.0
    # the mesh has the resolution the case asked for (mean hole-wall edge: 2.2 elements across, measured)
    assert 1.6 < ds["hole_elements_measured"].item() < 3.0
    assert ds["steps"].item() == 4 and ds["reached_time"].item() == pytest.approx(0.04)
    assert ds["kinetic_energy_solid"].values.max() == 0.0 and ds["elastic_energy"].values.max() == 0.0
    # the squeezed wall drives the urine (P_wall < 0: the urine at ~p_ref pushes back on the inward-moving
    # wall, and as much p_ref work leaves through the open ends); the net work is what the urine gains in
    # kinetic energy plus what it dissipates (kinetic energy theorem, tests/fsi/test_fluid_alone.py)
    p_wall, p_open = ds["prescribed_power"].values, ds["open_boundary_power"].values
    assert np.all(p_wall[1:] < 0) and np.all(p_open[1:] > 0)
    t, e = ds["time"].values, ds["kinetic_energy"].values
    net_work = np.sum(np.diff(t) * 0.5 * (p_wall + p_open)[1:] + np.diff(t) * 0.5 * (p_wall + p_open)[:-1])
    print(f"net work {net_work:.3e} J, kinetic energy gained {e[-1] - e[0]:.3e} J")
    assert 0 < e[-1] - e[0] < net_work
    assert 0 < ds["max_energy_ratio"].item() < 1.0
    assert ds["volume_error"].item() < 1e-2 and ds["min_jacobian"].item() > 0.9
    for name in ds.variables:
        assert {"units", "long_name"} <= set(ds[name].attrs), name


def test_a_broken_case_is_recorded_not_raised(cfg, rz_mesh):
    cfg["solver"]["mesh_motion"] = "laplace"        # refused by the engine while it builds the problem
    ds = S.run_case(cfg, S.Case("baseline"), mesh_path=rz_mesh, end=0.02)
    assert ds["outcome"].item() == "failed" and ds["limit"].item() == "exception"
    assert ds["diagnosis"].item().startswith("exception: ValueError: mesh motion: 'harmonic' or 'elastic'")
    assert ds["steps"].item() == 0 and math.isnan(ds["max_kinetic_energy"].item())


def test_case_files_hold_the_case_scalars_in_order(runs):
    """combine and the figures read the per-case scalars of CaseScalars, in its field order."""
    for ds in runs.values():
        assert tuple(k for k, v in ds.data_vars.items() if v.ndim == 0) == S.SCALARS
        assert ds["steps"].item() > 0


def test_the_package_reads_cases_and_datasets_without_dolfinx():
    """Config validation and the stability figures import the package; only run_case needs dolfinx."""
    code = ("import sys\nfor m in ('dolfinx', 'petsc4py', 'mpi4py', 'ufl'):\n    sys.modules[m] = None\n"
            "import ureterfsi.stability as S\nassert 'ureterfsi.stability.run' not in sys.modules\n"
            "S.cases, S.combine, S.SCALARS\n"
            "try:\n    S.run_case\nexcept ImportError:\n    print('ok')\n")
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert r.returncode == 0 and r.stdout.strip() == "ok", r.stderr


def test_matrix_dataset_and_stability_map(runs, hole_run, tmp_path):
    from ureterfsi.plotting.stability import stability_map
    from ureterfsi.plotting.style import save_figure

    paths = []
    for name, ds in (runs | {"hole": hole_run}).items():
        paths.append(tmp_path / f"{name}.nc")
        S.write_case(ds, paths[-1])
    m = S.combine(paths, {"stability": {}})
    assert list(m["case"].values) == ["baseline", "time_step_0.1", "load_amplitude_2e6", "hole_elements_2"]
    assert list(m["scene"].values) == ["rz", "rz", "rz", "holes"]
    assert m["kinetic_energy"].dims == ("case", "step") and m.sizes["step"] == 21
    assert list(m["outcome"].values)[2] == "failed" and m["axis"].values[1] == "time_step"
    for name in m.variables:
        assert {"units", "long_name"} <= set(m[name].attrs), name
    assert "config_hash" in m.attrs and "case_baseline_git_commit" in m.attrs
    S.write_case(m, tmp_path / "stability.nc")
    with xr.open_dataset(tmp_path / "stability.nc", decode_times=False) as back:
        assert str(back["diagnosis"].values[2]).startswith("ale_inversion")
    table = S.outcome_table(m)
    assert table.count("\n") == 5 and "ale_inversion" in table
    png = tmp_path / "stability_map.png"
    save_figure(stability_map(m), [png], dpi=60)
    assert png.stat().st_size > 10_000
