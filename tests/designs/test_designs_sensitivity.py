"""Design studies: the two-parameter map figure and Sobol' indices of a Saltelli design (SALib): the
expansion, the refusals, the indices through the design dataset, the Ishigami function's exact indices, and the
figures drawn from datasets of known values."""
from __future__ import annotations

import copy
from pathlib import Path

import numpy as np
import pytest
import xarray as xr
import yaml

from ureterfsi.config import ConfigError, load_config
from ureterfsi.designs.expand import saltelli_unit_sample, studies
from ureterfsi.designs.results import SOBOL_INDICES, add_sobol_indices, sobol_indices, study_dataset
from ureterfsi.data import cf as metadata
from ureterfsi.data.cf import VARIABLES
from ureterfsi.data.provenance import FORMAT_VERSION, FORMAT_VERSION_ATTR
from helpers.design_runs import stamp

REPO = Path(__file__).resolve().parents[2]
BASE = yaml.safe_load((REPO / "config" / "config.yaml").read_text())
BOUNDS = {"peak_traction": [3e4, 7e4], "wall_stiffness_scale": [0.5, 1.5]}


def saltelli(size=4, seed=2, bounds=BOUNDS) -> dict:
    return {"model": "3", "level": "coarse", "sample": {"method": "saltelli", "size": size, "seed": seed,
                                                        "bounds": copy.deepcopy(bounds)}}


def config_with(**specs) -> dict:
    return load_config(BASE, {"design_studies": specs})


def test_saltelli_expansion_is_salibs_sample_each_point_once():
    """N (2 D + 2) rows in SALib's order, scaled to the bounds; for D = 2 the rows B_A1 = A_B2 and B_A2 = A_B1
    repeat, so 4 N distinct points run."""
    st = studies(config_with(s=saltelli(size=4)))["s"]
    unit = saltelli_unit_sample(2, 4, 2)
    lo, hi = np.array([3e4, 0.5]), np.array([7e4, 1.5])
    assert st.kind == "saltelli" and len(st.rows) == 4 * 6 == unit.shape[0] and len(st.points) == 16
    values = {p.id: [p.values["peak_traction"], p.values["wall_stiffness_scale"]] for p in st.points}
    rows = np.array([values[r] for r in st.rows])
    assert np.allclose(rows, lo + unit * (hi - lo), rtol=1e-9, atol=0)
    blocks = np.array(st.rows).reshape(4, 6)        # per base row: A, A_B1, A_B2, B_A1, B_A2, B
    assert (blocks[:, 3] == blocks[:, 2]).all() and (blocks[:, 4] == blocks[:, 1]).all()
    assert len(set(blocks[:, [0, 1, 2, 5]].ravel())) == 16
    again = studies(config_with(s=saltelli(size=4, seed=3)))["s"]
    assert again.rows != st.rows


@pytest.mark.parametrize("spec,key,text", [
    (saltelli(size=6), "design_studies.s.sample.size", "power of 2, got 6"),
    (saltelli(bounds={"peak_traction": [3e4, 7e4]}), "design_studies.s.sample.bounds", "at least 2 parameters"),
    (saltelli(bounds={"peak_traction": [3e4, 7e4], "hole_pair_rotation": [0, 90]}),
     "design_studies.s.sample.bounds.hole_pair_rotation", "vary it on a grid"),
])
def test_saltelli_refusals(spec, key, text):
    with pytest.raises(ConfigError) as err:
        config_with(s=spec)
    msg = str(err.value)
    assert "\n" not in msg and msg.startswith(f"config error: {key}:") and text in msg, msg


def ishigami(x: np.ndarray, a=7.0, b=0.1) -> np.ndarray:
    return np.sin(x[:, 0]) + a * np.sin(x[:, 1]) ** 2 + b * x[:, 2] ** 4 * np.sin(x[:, 0])


def ishigami_indices(a=7.0, b=0.1) -> tuple[np.ndarray, np.ndarray]:
    """Exact S1, ST of the Ishigami function on [-pi, pi]^3 (Sobol' & Levitan 1999)."""
    v1 = 0.5 * (1 + b * np.pi ** 4 / 5) ** 2
    v2 = a ** 2 / 8
    v13 = b ** 2 * np.pi ** 8 * (1 / 18 - 1 / 50)          # 8 b^2 pi^8 / 225
    v = v1 + v2 + v13
    return np.array([v1, v2, 0.0]) / v, np.array([v1 + v13, v2, v13]) / v


def test_sobol_indices_of_the_ishigami_function():
    """A design dataset laid out as study_dataset lays out a Saltelli design (the point of each row), of the
    Ishigami function (a = 7, b = 0.1) at N = 1024: S1 and ST within SALib's 95 % intervals of the exact values."""
    params = ["peak_traction", "pulse_speed", "wall_stiffness_scale"]
    unit = saltelli_unit_sample(3, 1024, 11)
    y = ishigami(-np.pi + 2 * np.pi * unit)
    ds = xr.Dataset({"peak_outlet_flux": ("design", y),
                     "saltelli_point": ("saltelli_row", np.arange(y.size, dtype=np.int32))},
                    coords={p: ("design", unit[:, j]) for j, p in enumerate(params)})
    out = add_sobol_indices(ds, params, seed=5)
    s1, st = ishigami_indices()
    got = {k: out[k].sel(quantity="peak_outlet_flux").values for k in SOBOL_INDICES}
    print("\nIshigami S1", got["sobol_first_order"], "+-", got["sobol_first_order_conf"], "exact", s1,
          "\nST", got["sobol_total"], "+-", got["sobol_total_conf"], "exact", st)
    assert list(out["parameter"].values) == params and out["sobol_total"].dims == ("quantity", "parameter")
    assert (np.abs(got["sobol_first_order"] - s1) <= got["sobol_first_order_conf"]).all()
    assert (np.abs(got["sobol_total"] - st) <= got["sobol_total_conf"]).all()
    assert (got["sobol_first_order_conf"] < 0.15).all() and (got["sobol_total_conf"] < 0.15).all()   # not vacuous
    # the indices follow the rows: a shuffled design read through saltelli_point gives the same indices
    perm = np.random.default_rng(0).permutation(y.size)
    shuffled = xr.Dataset({"peak_outlet_flux": ("design", y[perm]),
                           "saltelli_point": ("saltelli_row", np.argsort(perm).astype(np.int32))})
    again = sobol_indices(shuffled, params, "peak_outlet_flux", seed=5)
    assert np.allclose(again["sobol_total"], got["sobol_total"], rtol=1e-12, atol=1e-15)


def _fake_run(path: Path, peak: float, disp: float) -> None:
    """A run file with what point_scalars and mesh_motion_variables read: an outlet flow peaking at `peak`, a wall displacement `disp`."""
    t = np.linspace(0.0, 0.02, 3)
    ds = xr.Dataset({"outlet_flux": ("time", peak * np.array([0.0, 1.0, 0.5])),
                     "max_wall_displacement": ("time", disp * np.array([0.0, 0.5, 1.0])),
                     "min_ale_jacobian": ("time", np.array([1.0, 0.9, 0.8]))},
                    coords={"time": ("time", t)}, attrs={"wall_time_s": 1.0, "config_hash": "x"})
    # as the run writer marks it (study_dataset reads run files through checked_io: format version and units)
    metadata.annotate(ds)
    ds.attrs[FORMAT_VERSION_ATTR] = FORMAT_VERSION
    ds.to_netcdf(path)


def test_study_dataset_of_a_saltelli_design_holds_salibs_indices(tmp_path):
    """Through study_dataset: the indices of each quantity equal SALib's on the full sample matrix (rows repeated,
    in SALib's order), with the registry's metadata."""
    from SALib.analyze import sobol

    cfg = config_with(s=saltelli(size=8) | {"rung_check": {"corners": "none"}})      # the indices alone
    st = studies(cfg)["s"]
    f = {"peak_outlet_flux": lambda x: 1e-9 * (1.5 + 2 * x[:, 0] / 7e4 + np.sin(3 * x[:, 1])),
         "peak_wall_displacement": lambda x: 1e-4 * x[:, 1] ** 2 * (x[:, 0] / 7e4)}
    paths = {}
    for p in st.points:
        x = np.array([[p.values["peak_traction"], p.values["wall_stiffness_scale"]]])
        paths[p.id] = tmp_path / f"{p.id}.nc"
        _fake_run(paths[p.id], f["peak_outlet_flux"](x)[0], f["peak_wall_displacement"](x)[0])
    ds = study_dataset(cfg, "s", stamp(st, paths))
    assert ds.sizes["design"] == 32 and ds.sizes["saltelli_row"] == 48
    values = {p.id: [p.values["peak_traction"], p.values["wall_stiffness_scale"]] for p in st.points}
    x = np.array([values[r] for r in st.rows])
    problem = {"num_vars": 2, "names": list(BOUNDS), "bounds": list(BOUNDS.values())}
    for q, fq in f.items():
        ref = sobol.analyze(problem, fq(x), calc_second_order=True, seed=2)
        for k, salib_key in SOBOL_INDICES.items():
            assert np.allclose(ds[k].sel(quantity=q).values, ref[salib_key], rtol=1e-9, atol=1e-12), (q, k)
    assert np.isnan(ds["sobol_total"].sel(quantity="peak_stent_von_mises").values).all()   # no stent stress recorded
    for k in ("saltelli_point", "quantity", "parameter", *SOBOL_INDICES):
        assert (ds[k].attrs["units"], ds[k].attrs["long_name"]) == VARIABLES[k], k
    from ureterfsi.data.cf import write_netcdf
    from ureterfsi.plotting.designs import sensitivity_figure

    write_netcdf(ds, tmp_path / "s.nc")                  # what rule design_sensitivity reads
    back = xr.load_dataset(tmp_path / "s.nc", decode_times=False)
    assert list(back["parameter"].values) == list(BOUNDS) and (back["saltelli_point"] == ds["saltelli_point"]).all()
    assert np.allclose(back["sobol_total"].values, ds["sobol_total"].values, equal_nan=True)
    fig = sensitivity_figure(back)
    assert fig.axes[0].get_xlabel() == "Sobol' index" and fig.axes[0].get_title() == "peak outlet flux"


def test_sobol_figure_draws_the_indices_and_their_intervals():
    from ureterfsi.plotting.designs import sobol_figure

    params, qs = ["peak_traction", "hole_diameter"], ["peak_outlet_flux", "backflow_volume"]
    vals = {k: np.array([[0.1, 0.5], [0.3, 0.2]]) + 0.01 * i for i, k in enumerate(SOBOL_INDICES)}
    ds = xr.Dataset({k: (("quantity", "parameter"), v) for k, v in vals.items()},
                    coords={"quantity": qs, "parameter": params})
    fig = sobol_figure(ds)
    for i, ax in enumerate(fig.axes[:2]):
        bars = [c for c in ax.containers if hasattr(c, "datavalues")]
        assert len(bars) == 2 and ax.get_title() == qs[i].replace("_", " ")
        for c, name in zip(bars, ("sobol_first_order", "sobol_total")):
            assert np.allclose(c.datavalues, vals[name][i])
            seg = c.errorbar.lines[2][0].get_segments()
            assert np.allclose([s[1, 0] - s[0, 0] for s in seg], 2 * vals[f"{name}_conf"][i])


def test_map_figure_plots_the_grid_values():
    """A 3 x 2 x 2 grid with a fixed fourth parameter: one map per quantity and value of the third parameter; each
    map's cells hold the dataset's values on the grid, the design points are marked, the colour bar carries the
    registry's units."""
    from ureterfsi.plotting.designs import map_figure

    grid = {"hole_diameter": [5e-4, 7e-4, 9e-4], "stricture_fraction": [0.0, 0.5], "hole_pair_spacing": [0.005, 0.01],
            "stricture_length": [0.004]}
    shape = [len(v) for v in grid.values()]
    i, j, k, _ = np.indices(shape)
    data = {"peak_outlet_flux": 1e-9 * (1 + i + 10 * j + 100 * k), "backflow_volume": 1e-12 * (i - j + 3 * k + 0.5)}
    data["backflow_volume"][2, 1, 0, 0] = np.nan                               # a failed point stays blank
    dims = list(grid)
    ds = xr.Dataset({q: (dims, v, {"units": VARIABLES[q][0]}) for q, v in data.items()}
                    | {"point_id": (dims, np.arange(np.prod(shape)).astype(str).reshape(shape))}, coords=grid)
    fig = map_figure(ds)
    maps = [ax for ax in fig.axes if ax.collections and ax.get_label() != "<colorbar>"]
    assert len(maps) == 4
    for n, ax in enumerate(maps):
        q, col = list(data)[n // 2], n % 2
        expected = np.ma.masked_invalid(data[q][:, :, col, 0].T)      # rows: stricture fraction, columns: hole diameter
        got = ax.collections[0].get_array()
        assert got.shape == expected.shape and np.ma.allequal(got, expected), (q, col)
        assert (np.ma.getmaskarray(got) == np.ma.getmaskarray(expected)).all()
        x, y = ax.lines[0].get_data()
        assert sorted(zip(x, y)) == sorted((a, b) for a in grid["hole_diameter"] for b in grid["stricture_fraction"])
        assert ax.get_xlabel() == "hole diameter [m]" and ax.get_ylabel() == "stricture fraction [1]"
        assert f"hole pair spacing = {grid['hole_pair_spacing'][col]:g} m" in ax.get_title()
        assert ax.collections[0].colorbar.ax.get_ylabel() == f"{q.replace('_', ' ')} [{VARIABLES[q][0]}]"
    with pytest.raises(ValueError, match="two grid parameters"):
        map_figure(ds.isel(stricture_fraction=[0], hole_pair_spacing=[0]))


def test_dry_run_of_a_saltelli_study(tmp_path):
    """D = 2, N = 4: 24 rows, 16 distinct points, each one solve on its own wall motion; the Sobol' figure."""
    from helpers.design_runs import dry_run

    cfg = copy.deepcopy(BASE)
    cfg["design_studies"] = {"s": saltelli(size=4)}
    counts = dry_run(tmp_path, cfg, "design_s")
    # and the rung check's 4 corners of the bounds on the 10 mm segment (one mesh, a wall each, two solves each)
    assert counts == {"design_solve": 16, "design_mesh": 1 + 1, "design_wall_motion": 16 + 4, "design_dataset": 1,
                      "design_corner_solve": 2 * 4, "design_rung_check": 1, "design_figures": 1, "design_sensitivity": 1, "design_s": 1}, counts


def test_point_scalars_carry_the_end_conditions_outcome():
    """The peak pelvic pressure and the reflux volumes (their last values: they accumulate from t = 0) of a run with
    a renal pelvis; NaN for a run with the paper's open ends (no such record)."""
    from ureterfsi.designs.results import END_CONDITIONS, point_scalars

    t = np.linspace(0.0, 0.04, 3)
    base = {"outlet_flux": ("time", [0.0, 1e-9, 5e-10]), "max_wall_displacement": ("time", [0.0, 1e-5, 2e-5])}
    ends = {"pelvic_pressure": ("time", [130.0, 1114.0, 1090.0]),
            "stent_lumen_reflux_volume": ("time", [0.0, 2e-10, 5e-10]),
            "annulus_reflux_volume": ("time", [0.0, 3e-8, 6.6e-8])}
    got = point_scalars(xr.Dataset(base | ends, coords={"time": t}))
    assert (got["peak_pelvic_pressure"], got["reflux_volume_lumen"], got["reflux_volume_annulus"]) == (1114.0, 5e-10, 6.6e-8)
    open_ends = point_scalars(xr.Dataset(base, coords={"time": t}))
    assert all(np.isnan(open_ends[k]) for k in END_CONDITIONS)
