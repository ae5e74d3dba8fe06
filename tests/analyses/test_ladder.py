"""Fidelity ladder: errors of a rung against the reference, scene choices, dataset, table, figure.

Runs are built by the study's own probes_dataset from analytic values (tests/analyses/test_aggregate_figures.py):
a rung that equals the reference has error 0; a rung scaled by (1 + eps) has error eps for every quantity;
a coarser time grid of the same smooth curves has the interpolation error only; a half model's two holes
per pair are matched to the quarter model's one.
"""
import numpy as np
import pytest
import xarray as xr

from helpers.synthetic import synthetic_run
from ureterfsi.analyses import ladder
from ureterfsi.plotting.style import save_figure
from ureterfsi.plotting import ladder as plotting_ladder
from ureterfsi.config import load_config

SCALED = ("outlet_flux", "stent_max_von_mises", "stent_von_mises_line", "wall_radial_displacement",
          "hole_velocity_y", "hole_flux")


def scaled(ds: xr.Dataset, eps: float) -> xr.Dataset:
    out = ds.copy(deep=True)
    for v in SCALED:
        out[v] = (out[v] * (1.0 + eps)).assign_attrs(out[v].attrs)   # units kept, as the run writer has them
    return out


@pytest.fixture
def cfg(repo_root):
    c = load_config(repo_root / "config/config.yaml")
    c["ladder"]["end"] = 1.0
    return c


def test_identical_rung_has_zero_error_and_scaled_rung_its_scale(cfg):
    ref = synthetic_run(cfg, "3", end=1.0)
    for q in ladder.QUANTITIES:
        assert ladder.relative_error(ref, ref, q) == 0.0
    run = scaled(ref, 0.03)
    for q in SCALED:
        assert ladder.relative_error(ref, run, q) == pytest.approx(0.03, rel=1e-9), q


def test_coarser_time_grid_is_interpolated_onto_the_reference_times(cfg):
    ref = synthetic_run(cfg, "3", end=1.0, dt=0.01)
    coarse = synthetic_run(cfg, "3", end=1.0, dt=0.04)
    e = ladder.relative_error(ref, coarse, "outlet_flux")
    # linear interpolation of A sin t over h = 0.04: error <= h^2/8 max|sin''| / max|sin| on [0, 1]
    assert 0 < e <= 0.04**2 / 8 / np.sin(1.0) * 1.01
    assert ladder.relative_error(ref, coarse, "stent_von_mises_line") == pytest.approx(0.0, abs=1e-15)


def test_half_model_holes_are_matched_to_the_quarter_model(cfg):
    quarter = synthetic_run(cfg, "3", end=0.5, symmetry="quarter")
    half = synthetic_run(cfg, "3", end=0.5, symmetry="half")
    assert half.sizes["hole"] == 2 * quarter.sizes["hole"]
    assert ladder.relative_error(quarter, half, "hole_flux") == pytest.approx(0.0, abs=1e-15)


def test_cheapest_rung_within_tolerance_is_chosen(cfg):
    ref = synthetic_run(cfg, "3", end=1.0, wall_time=100.0)
    runs = {"fully_coupled": ref,
            "one_way": scaled(synthetic_run(cfg, "3", end=1.0, wall_time=20.0), 0.01),
            "one_way_dt4": scaled(synthetic_run(cfg, "3", end=1.0, wall_time=5.0), 0.2)}
    err = xr.DataArray([[ladder.relative_error(ref, r, q) for q in SCALED] for r in runs.values()],
                       dims=("rung", "quantity"), coords={"rung": list(runs), "quantity": list(SCALED)})
    cost = xr.DataArray([float(r.attrs["wall_time_s"]) for r in runs.values()], dims="rung",
                        coords={"rung": list(runs)})
    pick = ladder.select_rungs(err, cost, {"loose": {"quantities": ["outlet_flux"], "tolerance": 0.5},
                                           "usual": {"quantities": ["outlet_flux", "hole_flux"], "tolerance": 0.05},
                                           "strict": {"quantities": ["hole_velocity_y"], "tolerance": 1e-3}})
    assert pick["loose"][0] == "one_way_dt4" and pick["loose"][1] == pytest.approx(0.2)
    assert pick["usual"][0] == "one_way" and pick["usual"][1] == pytest.approx(0.01)
    assert pick["strict"] == ("fully_coupled", 0.0)


def test_ladder_dataset_table_and_figure(cfg, tmp_path):
    cfg["ladder"]["rungs"] = {"fully_coupled": {"fidelity": "fully_coupled", "symmetry": "quarter",
                                                "level": "coarse", "dt": 0.01},
                              "one_way": {"fidelity": "one_way", "symmetry": "quarter", "level": "coarse", "dt": 0.01}}
    ref = synthetic_run(cfg, "3", end=1.0, wall_time=100.0)
    one = scaled(synthetic_run(cfg, "3", end=1.0, wall_time=20.0), 0.02)
    one.attrs["one_way_max_stent_displacement"] = 4e-8
    paths = {}
    for name, ds in (("fully_coupled", ref), ("one_way", one)):
        paths[name] = tmp_path / f"{name}.nc"
        ds.to_netcdf(paths[name])
    ds = ladder.ladder_dataset(paths, cfg)
    assert ds["error"].dims == ("rung", "quantity")
    assert float(ds["error"].sel(rung="one_way", quantity="outlet_flux")) == pytest.approx(0.02)
    # every rung against every other: the reference column is `error`, the diagonal is zero
    np.testing.assert_array_equal(ds["pairwise_error"].sel(against="fully_coupled").values, ds["error"].values)
    assert float(ds["pairwise_error"].sel(rung="fully_coupled", against="one_way", quantity="outlet_flux")) \
        == pytest.approx(0.02 / 1.02)
    assert float(abs(ds["pairwise_error"].sel(rung="one_way", against="one_way")).max()) == 0.0
    assert set(ds["chosen_rung"].values) == {"one_way"}               # every scene tolerates 5 %
    for name, var in ds.variables.items():
        assert var.attrs.get("units") is not None and var.attrs.get("long_name"), name
    assert ds.attrs["reference"] == "fully_coupled" and ds.attrs["run_one_way_one_way_max_stent_displacement"] == 4e-8
    table = ladder.ladder_table(ds)
    assert "| one_way | one_way | quarter | coarse |" in table and "fig04_outlet_flow" in table
    # the default study runs use the one_way rung; its error is checked against tolerance and the config record
    assert ds.attrs["default_rung"] == "one_way"
    assert float(ds["default_error"].sel(scene="fig04_outlet_flow")) == pytest.approx(0.02)
    recorded = float(ds["recorded_error"].sel(scene="fig04_outlet_flow"))
    assert recorded == cfg["scenes"]["fig04_outlet_flow"]["measured_error"]
    assert "within tolerance, " + ("matches" if ladder.recorded_error_agrees(recorded, 0.02) else "differs") in table
    out = [tmp_path / "pareto.png"]
    save_figure(plotting_ladder.ladder_pareto(ds), out)
    assert out[0].stat().st_size > 1000


def test_overlay_figure_draws_every_rung_of_every_quantity(cfg, tmp_path):
    """The overlay's six panels each hold the reference and the other rung, the latter 2 % above (the scaled run),
    the hole the reference's largest-flow hole and the wall profile the last probe time's."""
    ref = synthetic_run(cfg, "3", end=1.0, wall_time=100.0)
    runs = {"fully_coupled": ref, "one_way": scaled(synthetic_run(cfg, "3", end=1.0, wall_time=20.0), 0.02)}
    fig = plotting_ladder.ladder_overlay(runs, "fully_coupled")
    hole = int(np.abs(ref["hole_flux"]).max("time").argmax())
    expected = {"outlet_flux": ref["outlet_flux"].values, "inlet_flux": ref["inlet_flux"].values,
                "hole_flux": ref["hole_flux"].isel(hole=hole).values,
                "stent_max_von_mises": ref["stent_max_von_mises"].values,
                "max_wall_displacement": ref["max_wall_displacement"].values,
                "wall_radial_displacement": ref["wall_radial_displacement"].isel(probe_time=-1).values}
    for ax, q in zip(fig.axes, plotting_ladder.LADDER_OVERLAY):
        lines = ax.get_lines()
        assert [ln.get_linestyle() for ln in lines] == ["-", "--"], q
        np.testing.assert_allclose(lines[0].get_ydata(), expected[q], err_msg=q)
        factor = 1.02 if q in SCALED else 1.0
        np.testing.assert_allclose(lines[1].get_ydata(), factor * expected[q], rtol=1e-12, err_msg=q)
    out = [tmp_path / "overlay.png"]
    save_figure(fig, out)
    assert out[0].stat().st_size > 1000


def test_default_rung_and_recorded_error_checks(cfg):
    """The rung of the default runs is found by fidelity, symmetry, level and time step; a recorded error
    agrees with a measurement to 10 %; a default error above a tolerance is flagged in the table."""
    assert ladder.default_rung(cfg) == "one_way"
    cfg["time"]["dt"] = 0.02
    assert ladder.default_rung(cfg) == "one_way_dt2"
    cfg["study"]["fidelity"] = "fully_coupled"
    assert ladder.default_rung(cfg) is None
    assert ladder.recorded_error_agrees(1.9e-2, 1.92e-2) and not ladder.recorded_error_agrees(1.9e-2, 2.5e-2)
    assert ladder.recorded_error_agrees(5.4e-5, 1.2e-4)          # absolute floor for tiny errors


def test_exceeded_tolerance_and_stale_record_are_flagged(cfg, tmp_path):
    cfg["ladder"]["rungs"] = {"fully_coupled": {"fidelity": "fully_coupled", "symmetry": "quarter",
                                                "level": "coarse", "dt": 0.01},
                              "one_way": {"fidelity": "one_way", "symmetry": "quarter", "level": "coarse", "dt": 0.01}}
    paths = {"fully_coupled": tmp_path / "ref.nc", "one_way": tmp_path / "one.nc"}
    synthetic_run(cfg, "3", end=1.0, wall_time=100.0).to_netcdf(paths["fully_coupled"])
    scaled(synthetic_run(cfg, "3", end=1.0, wall_time=20.0), 0.08).to_netcdf(paths["one_way"])
    table = ladder.ladder_table(ladder.ladder_dataset(paths, cfg))
    row = next(line for line in table.splitlines() if line.startswith("| fig04_outlet_flow"))
    assert "EXCEEDS tolerance, differs" in row
