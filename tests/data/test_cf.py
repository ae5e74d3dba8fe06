"""CF 1.8 compliance of the datasets, checked by IOOS compliance-checker (--test=cf:1.8), and the
post-processing modules importable without dolfinx."""
from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import netCDF4
import numpy as np
import pytest
import xarray as xr

from ureterfsi.data import cf as metadata
from ureterfsi.analyses.gci import gci_dataset
from helpers.cf_check import cf_errors
from helpers.design_runs import stamp, stamp_corners
from helpers.synthetic import convergence_dataset

def test_encoding_follows_cf(tmp_path):
    ds = xr.Dataset({"cells": ("level", np.array([10, 20, 40], dtype=np.int64)),
                     "wall_time": ("level", [1.0, 2.0, np.nan]),
                     "hole_flux": (("hole", "time"), np.arange(6.0).reshape(3, 2))},
                    coords={"level": ("level", np.array(["coarse", "medium", "fine"], dtype=object)),
                            "time": ("time", [0.0, 1.0])})
    metadata.annotate(ds)
    path = tmp_path / "x.nc"
    metadata.write_netcdf(ds, path, title="encoding test")
    with netCDF4.Dataset(path) as nc:
        assert nc["cells"].dtype == np.int32
        assert "_FillValue" not in nc["time"].ncattrs()
        assert nc["time"].standard_name == "time"
        assert nc.Conventions == "CF-1.8" and nc.title == "encoding test"
        assert "stented ureter" in nc.references and nc.history.split(": ", 1)[1]
        assert nc["hole_flux"].dimensions == ("hole", "time")          # CF §2.4: time right of the others
    with xr.open_dataset(path, decode_times=False) as back:
        np.testing.assert_array_equal(back["hole_flux"], ds["hole_flux"])
    with pytest.raises(ValueError, match="'hole_flux'.*`time` last"):   # producers build time last
        metadata.write_netcdf(ds.transpose("time", "hole", "level"), tmp_path / "y.nc")
    assert not (tmp_path / "y.nc").exists()
    with pytest.raises(ValueError, match="'big'.*int32"):
        metadata.encoding(xr.Dataset({"big": ("n", np.array([2 ** 40]))}))
    with pytest.raises(KeyError, match="'unknown'"):
        metadata.annotate(xr.Dataset({"unknown": ("n", [1.0])}))


def stability_case(name: str, axis: str, steps: int) -> xr.Dataset:
    """A synthetic stability case file with the layout of ureterfsi.stability.run_case (every CF name: the
    per-case scalars, the per-step series along `step` with `time`)."""
    from ureterfsi import stability as S

    per_step = {"time", *S.PER_STEP}
    strings = {"axis": axis, "value_label": "0.1", "outcome": "stable", "limit": "", "diagnosis": "",
               "mesh_level": "coarse", "scene": "rz"}
    scalars = {k: ((), strings.get(k, 1.0)) for k in S.SCALARS}
    series = {k: ("step", np.linspace(0.0, 1.0, steps)) for k in per_step - {"time"}}
    ds = xr.Dataset(scalars | series, coords={"step": np.arange(steps), "time": ("step", np.linspace(0, 0.1, steps))})
    ds = ds.assign_coords(case=name)
    metadata.annotate(ds)
    ds.attrs.update(case=name, title=f"synthetic stability case {name}")
    return ds


def design_study(cfg, tmp_path, saltelli=False) -> xr.Dataset:
    """The dataset of a 2 x 2 full-factorial design study over synthetic runs of model 3 (or of a Saltelli
    design of N = 2 over two parameters: 12 rows, 8 points, with its Sobol' indices)."""
    from helpers.synthetic import synthetic_run
    from ureterfsi.designs import results as design_results
    from ureterfsi.designs.expand import studies
    from ureterfsi.config import load_config

    grid = {"model": "3", "level": "coarse",
            "grid": {"mode": "full_factorial", "parameters": {"hole_diameter": [5e-4, 7e-4],
                                                               "hole_pair_spacing": [0.005, 0.01]}}}
    if saltelli:
        grid = {"model": "3", "level": "coarse", "sample": {"method": "saltelli", "size": 2, "seed": 0, "bounds": {
            "hole_diameter": [5e-4, 7e-4], "peak_traction": [4e4, 6e4]}}}
    cfg = load_config(cfg, {"design_studies": {"s": grid}})
    paths = {}
    st = studies(cfg)["s"]
    for p in st.points:
        paths[p.id] = tmp_path / f"{p.id}.nc"
        metadata.write_netcdf(synthetic_run(cfg, "3", end=cfg["time"]["end"]), paths[p.id])
    corners = {}                                   # the rung check's corners (ureterfsi.designs.rung_check)
    for c in st.check.corners:
        corners[c.id] = (tmp_path / f"{c.id}_rung.nc", tmp_path / f"{c.id}_ref.nc")
        for k, f in enumerate(corners[c.id]):
            metadata.write_netcdf(synthetic_run(c.config, "3", end=c.config["time"]["end"], wall_time=1.0 + k), f)
    return design_results.study_dataset(cfg, "s", stamp(st, paths), design_results.rung_check_dataset(cfg, "s", stamp_corners(st, corners)))


KINDS = ("run", "models", "ladder", "mesh_convergence", "gci", "wall_motion", "stability_case", "stability",
         "design_study", "saltelli_study")


@pytest.mark.parametrize("kind", KINDS)
def test_dataset_passes_cf_checker(kind, tmp_path, repo_root):
    """Every dataset kind the pipeline writes as netCDF (the wall calibration is a JSON file) has 0 errors and
    0 medium-priority warnings (among them §2.4, the dimension order: `time` right of `hole`, `model`, ...)."""
    from ureterfsi.config import load_config

    cfg = load_config(repo_root / "config/config.yaml")
    if kind in ("run", "models", "ladder"):
        from helpers.synthetic import synthetic_run
        from ureterfsi.analyses import aggregate
        from ureterfsi.analyses import ladder

        runs = {m: synthetic_run(cfg, m, end=1.0, wall_time=10.0) for m in ("1", "3")}
        paths = {}
        for m, run in runs.items():
            paths[m] = tmp_path / f"run{m}.nc"
            metadata.write_netcdf(run, paths[m])
        if kind == "run":
            ds = runs["3"]
        elif kind == "models":
            ds = aggregate.combine_models(list(paths.values()), cfg)
        else:
            cfg["ladder"]["end"] = 1.0
            cfg["ladder"]["rungs"] = {r: {"fidelity": r, "symmetry": "quarter", "level": "coarse", "dt": 0.01}
                                      for r in ("fully_coupled", "one_way")}
            ds = ladder.ladder_dataset({"fully_coupled": paths["3"], "one_way": paths["3"]}, cfg)
    elif kind == "mesh_convergence":
        ds = convergence_dataset()[0]
    elif kind == "gci":
        ds = gci_dataset(convergence_dataset()[0])
    elif kind == "wall_motion":
        from ureterfsi.study.oneway import WallHistory

        t, zi, zo = np.linspace(0, 0.1, 5), np.linspace(0, 0.05, 7), np.linspace(0, 0.05, 9)
        w = WallHistory(t, zi, *(np.random.default_rng(k).normal(size=(5, 7)) * 1e-4 for k in range(4)),
                        zo, np.zeros((5, 9)))
        ds = w.to_dataset(cfg)
    elif kind == "stability_case":
        ds = stability_case("baseline", "none", 4)
    elif kind == "stability":
        from ureterfsi import stability as S

        ds = S.combine([stability_case("baseline", "none", 4), stability_case("time_step_0.1", "time_step", 3)])
    else:
        ds = design_study(cfg, tmp_path, saltelli=kind == "saltelli_study")
        assert kind == "design_study" or ds.sizes["saltelli_row"] == 12 and "sobol_total" in ds
    path = tmp_path / f"{kind}.nc"
    metadata.write_netcdf(ds, path)
    errors, warnings = cf_errors(path)
    print(f"{kind}: {errors} errors, {warnings} warnings")
    report = json.loads(Path(str(path) + ".cc.json").read_text())["cf:1.8"]
    assert errors == 0, report["high_priorities"]
    assert warnings == 0, [r for r in report["medium_priorities"] if r["msgs"]]
    if kind == "wall_motion":           # read back in the solver's layout (time first) whatever the file's order
        with xr.open_dataset(path, decode_times=False) as back:
            h = WallHistory.from_dataset(back.load(), cfg, 0.1, 0.025)
        for name in ("inner_ur", "inner_uz", "inner_vr", "inner_vz", "outer_ur"):
            np.testing.assert_array_equal(getattr(h, name), getattr(w, name), err_msg=name)


def test_time_coordinate_is_cf_and_read_in_seconds(tmp_path):
    """`time` is written as a CF time coordinate (units '<unit> since <epoch>', calendar) and read back by the
    package's reader as seconds from the run's start, not as dates."""
    from helpers.synthetic import synthetic_run
    from ureterfsi.data.checked import RUN_FILE, open_netcdf
    from ureterfsi.config import load_config

    cfg = load_config(Path(__file__).resolve().parents[2] / "config/config.yaml")
    run = synthetic_run(cfg, "3", end=0.1)
    path = tmp_path / "run.nc"
    metadata.write_netcdf(run, path)
    with netCDF4.Dataset(path) as nc:
        assert nc["time"].units == "s since 2000-01-01 00:00:00" and nc["time"].calendar == metadata.CALENDAR
    back = open_netcdf(path, RUN_FILE)
    assert back["time"].dtype.kind == "f"
    np.testing.assert_allclose(back["time"].values, run["time"].values, rtol=0, atol=0)


def test_postprocessing_imports_without_dolfinx():
    code = ("import sys\nfor m in ('dolfinx', 'petsc4py', 'mpi4py', 'ufl'):\n    sys.modules[m] = None\n"
            "import ureterfsi.data.cf, ureterfsi.analyses.aggregate, ureterfsi.plotting.paper, ureterfsi.analyses.gci\nprint('ok')")
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert r.returncode == 0 and r.stdout.strip() == "ok", r.stderr


def test_every_registry_table_gives_udunits_units_and_a_long_name():
    """Every entry of the registry's tables (the templated ones too) has units UDUNITS parses and a long_name."""
    import cf_units

    from ureterfsi.designs import space as designs

    tables = {"VARIABLES": metadata.VARIABLES, "FIELD_VARIABLES": metadata.FIELD_VARIABLES,
              "WALL_MOTION_VARIABLES": metadata.WALL_MOTION_VARIABLES,
              "DESIGN_PARAMETERS": metadata.DESIGN_PARAMETERS,
              "gci_variables": metadata.gci_variables(False, "fine", "medium", "coarse", ("monotone",)),
              "ladder_variables": metadata.ladder_variables("reference", "default"),
              "gci_quantity_variables": metadata.gci_quantity_variables("peak_outlet_flux",
                                                                        *metadata.cf_meta("peak_outlet_flux"))}
    for table_name, table in tables.items():
        for name, (units, long_name) in table.items():
            cf_units.Unit(units)          # raises on units UDUNITS cannot parse
            assert isinstance(long_name, str) and long_name.strip(), (table_name, name)
    assert metadata.gci_variables(True, "f", "m", "c", ())["h"][0] == "1"
    assert metadata.ladder_variables("fc")["error"][1].endswith("'fc'")
    # the design parameters take their units and long_name from the registry, one entry each
    assert set(designs.PARAMETERS) == set(metadata.DESIGN_PARAMETERS)
    for name, p in designs.PARAMETERS.items():
        assert (p.units, p.long_name) == metadata.DESIGN_PARAMETERS[name]
    with pytest.raises(KeyError, match="'nope'"):
        metadata.cf_meta("nope", metadata.FIELD_VARIABLES)
