"""Study datasets: per-run probe files (ureterfsi.study) combined across models and across mesh levels.

combine_models  runs of one mesh level, new dim `model` ("1".."4", with a `model_label` coordinate as in
                Table 1). Runs may have different time grids (step halving); every time series is put on
                the union of the runs' step times by linear interpolation (NaN outside a run's own time
                range), recorded in the dataset attrs. Variables that exist only in stented runs are NaN
                for the stent-free model. Per-hole variables are padded to the largest hole count
                (`hole_z`, `hole_side` become (model, hole) coordinates, NaN where a model has fewer
                holes); per-step solver records are padded along `step`.
combine_levels  the mesh-convergence study (paper §3.1, Fig. 3): dim `level` ordered as in the config,
                the stent probe-line von Mises stress at one probe time, and per-level scalars.

Every variable carries CF `units` and `long_name`; the datasets carry provenance_attrs, the provenance
of every input run (attrs `run_<model>_*` / `run_<level>_*`) and are written atomically.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np
import xarray as xr

from ureterfsi.data.checked import RUN_FILE, BadFile, Contract, open_netcdf
from ureterfsi.data.cf import VARIABLES, annotate, at_time, cf_attrs, write_netcdf
from ureterfsi.data.provenance import provenance_attrs

DEFAULT_LABELS = {"1": "No stent", "2": "5 mm", "3": "10 mm", "4": "25 mm"}
TIME_DECIMALS = 9            # times equal to 1 ns are the same instant (probe times, union grid)
# run attrs that are not copied per run (dataset-level metadata of the run file)
_SKIP_RUN_ATTRS = ("Conventions", "title")

# what the readers of the study datasets (figures, ureterfsi.analyses.gci) rely on
MODELS_DATASET = Contract("models dataset", attrs=("mesh_level", "models"),
                          variables=("model", "model_label", "time", "z", "probe_time", "outlet_flux",
                                     "wall_radial_displacement", "outlet_hole_z"), units=VARIABLES)
CONVERGENCE_DATASET = Contract("mesh-convergence dataset", attrs=("model", "levels", "probe_time"),
                               variables=("level", "z", "stent_von_mises_line", "cells", "dofs",
                                          "peak_outlet_flux", "peak_stent_max_von_mises"))


def open_run(path) -> xr.Dataset:
    """A per-run probe dataset (ureterfsi.study), checked (RUN_FILE), loaded into memory (the file is closed)."""
    return open_netcdf(path, RUN_FILE)


def _label(model: str, cfg: dict | None) -> str:
    if cfg is not None and model in cfg.get("models", {}):
        return str(cfg["models"][model]["label"])
    return DEFAULT_LABELS.get(model, f"model {model}")


def _run_attrs(prefix: str, attrs: dict) -> dict:
    out = {}
    for k, v in attrs.items():
        if k in _SKIP_RUN_ATTRS:
            continue
        if isinstance(v, (bool, np.bool_)):
            v = int(v)
        out[f"run_{prefix}_{k}"] = v
    return out


def _interp(t_new: np.ndarray, t: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Linear interpolation of y(t) (time along the last axis, CF §2.4) onto t_new; NaN outside [t0, t1]."""
    y = np.asarray(y, dtype=float)
    flat = y.reshape(-1, len(t))
    out = np.full((flat.shape[0], len(t_new)), np.nan)
    inside = (t_new >= t[0] - 10.0 ** -TIME_DECIMALS) & (t_new <= t[-1] + 10.0 ** -TIME_DECIMALS)
    for j in range(flat.shape[0]):
        out[j, inside] = np.interp(t_new[inside], t, flat[j])
    return out.reshape(y.shape[:-1] + (len(t_new),))


def _clean_time(run: xr.Dataset) -> xr.Dataset:
    """Sorted, unique times (a resumed run could repeat a step; the last record wins)."""
    t = np.round(run["time"].values.astype(float), TIME_DECIMALS)
    order = np.argsort(t, kind="stable")
    t_sorted = t[order]
    keep = np.r_[t_sorted[1:] != t_sorted[:-1], True]
    return run.isel(time=order[keep]).assign_coords(time=t_sorted[keep])


def _source(run: xr.Dataset) -> str:
    """The file a run was read from (checked_io.open_netcdf records it)."""
    return str(run.encoding.get("source", "<run in memory>"))


def check_identity(run: xr.Dataset, expect: dict) -> None:
    """The run's attributes (model, mesh_level, fidelity, symmetry) are those `expect` names: a run file of
    another model, level, rung or symmetry copied into a run's place is refused in one line naming it."""
    got = {k: str(run.attrs.get(k)) for k in expect}
    if got != {k: str(v) for k, v in expect.items()}:
        def what(d):
            return ", ".join(f"{k} {d[k]}" for k in expect)
        raise BadFile(_source(run), f"a run of {what(got)}, but this file is the run of {what(expect)}")


def _runs_by(paths, attr: str, expect: dict | None = None) -> dict:
    """Run files keyed by one attribute (model, mesh_level); a duplicate key or no file is an error. `expect`:
    {path: the attributes the run at that path must have} (check_identity)."""
    runs = {}
    for p in paths:
        run = open_run(p)
        if expect and str(p) in expect:
            check_identity(run, expect[str(p)])
        key = str(run.attrs[attr])
        if key in runs:
            raise BadFile(p, f"two runs with {attr} {key}: this one and {runs[key].encoding.get('source')}")
        runs[key] = run
    if not runs:
        raise ValueError(f"no run file to combine by {attr}")
    return runs


def combine_models(paths, cfg: dict | None = None, time_grid: str = "union", expect: dict | None = None) -> xr.Dataset:
    """Runs of one mesh level combined along `model` (see the module docstring).

    time_grid: "union" (every step time of every run) or "nominal" (0, dt, ..., end from cfg["time"]).
    expect: {path: the attributes its run must have} (check_identity; rule aggregate_models passes them).
    """
    runs = {m: _clean_time(run) for m, run in _runs_by(paths, "model", expect).items()}
    first = next(iter(runs.values()))
    for r in runs.values():   # a file of another level in this level's place is named
        if str(r.attrs["mesh_level"]) != str(first.attrs["mesh_level"]):
            raise BadFile(_source(r), f"a run of mesh level {r.attrs['mesh_level']!r}, combined with level "
                                      f"{first.attrs['mesh_level']!r} ({_source(first)}): runs of different mesh "
                                      f"levels cannot be combined along model")
    models = sorted(runs, key=lambda m: (len(m), m))

    if time_grid == "union":
        t = np.unique(np.concatenate([r["time"].values for r in runs.values()]))
        grid_doc = ("union of the step times of all runs; every run linearly interpolated onto it "
                    "(NaN outside the run's own time range)")
    elif time_grid == "nominal":
        if cfg is None:
            raise ValueError("time_grid='nominal' needs the configuration")
        dt, end = float(cfg["time"]["dt"]), float(cfg["time"]["end"])
        t = np.round(np.arange(0.0, end + 0.5 * dt, dt), TIME_DECIMALS)
        grid_doc = ("nominal grid 0, dt, ..., end of config time; every run linearly interpolated onto it "
                    "(NaN outside the run's own time range)")
    else:
        raise ValueError(f"unknown time_grid {time_grid!r}; use 'union' or 'nominal'")

    probe_t = np.unique(np.concatenate([np.round(r["probe_time"].values.astype(float), TIME_DECIMALS)
                                        for r in runs.values()]))
    ref = next(iter(runs.values()))
    z = ref["z"].values
    for m, r in runs.items():
        if r.sizes["z"] != z.size or not np.allclose(r["z"].values, z):
            raise BadFile(_source(r), f"run of model {m} has a different probe line z than {_source(ref)}")
    stented = [m for m in models if "hole_offset" in runs[m].coords]
    hole_offset = runs[stented[0]]["hole_offset"].values if stented else None
    n_hole = max((runs[m].sizes.get("hole", 0) for m in models), default=0)
    n_step = max(runs[m].sizes.get("step", 0) for m in models)

    names = []
    for m in models:
        for v in runs[m].data_vars:
            if v not in names:
                names.append(v)
    shapes = {"time": len(t), "probe_time": len(probe_t), "z": len(z), "step": n_step,
              "hole": n_hole, "hole_offset": 0 if hole_offset is None else len(hole_offset)}
    data_vars = {}
    for v in names:
        dims = next(runs[m][v].dims for m in models if v in runs[m])
        arr = np.full((len(models),) + tuple(shapes[d] for d in dims), np.nan)
        for i, m in enumerate(models):
            r = runs[m]
            if v not in r:
                continue
            da = r[v]                  # in the same dimension order in every run (one producer)
            if "probe_time" in dims:   # align probe times (a run may lack one, e.g. a shorter run)
                pt = np.round(r["probe_time"].values.astype(float), TIME_DECIMALS)
                idx = np.searchsorted(probe_t, pt)
                vals = da.values.astype(float)
                sub = np.full((len(probe_t),) + vals.shape[1:], np.nan)
                sub[idx] = vals
            elif "time" in dims:
                sub = _interp(t, r["time"].values, da.values)
            else:
                sub = da.values.astype(float)
            if "hole_offset" in dims and not np.allclose(r["hole_offset"].values, hole_offset):
                raise BadFile(_source(r), f"run of model {m} has a different hole_offset grid")
            sl = tuple(slice(0, s) for s in sub.shape)
            arr[(i,) + sl] = sub
        data_vars[v] = (("model",) + dims, arr)

    coords = {"model": ("model", np.array(models, dtype=object)),
              "model_label": ("model", np.array([_label(m, cfg) for m in models], dtype=object)),
              "time": ("time", t), "probe_time": ("probe_time", probe_t), "z": ("z", z)}
    if n_step:
        coords["step"] = ("step", np.arange(n_step))
    if hole_offset is not None:
        coords["hole_offset"] = ("hole_offset", hole_offset)
    if n_hole:
        hz = np.full((len(models), n_hole), np.nan)
        hs = np.full((len(models), n_hole), np.nan)
        for i, m in enumerate(models):
            if "hole_z" in runs[m].coords:
                k = runs[m].sizes["hole"]
                hz[i, :k] = runs[m]["hole_z"].values
                hs[i, :k] = runs[m]["hole_side"].values
        coords.update(hole=("hole", np.arange(n_hole)), hole_z=(("model", "hole"), hz),
                      hole_side=(("model", "hole"), hs))
    ds = annotate(xr.Dataset(data_vars, coords=coords))
    ds["outlet_hole_z"] = xr.DataArray(
        [float(runs[m].attrs.get("outlet_hole_z", np.nan)) for m in models], dims="model",
        attrs=cf_attrs("outlet_hole_z"))

    attrs = {}
    for m in models:
        attrs.update(_run_attrs(m, runs[m].attrs))
        attrs[f"run_{m}_source"] = Path(runs[m].encoding["source"]).name
    ds.attrs.update(provenance_attrs(cfg or {}, mesh_level=str(first.attrs["mesh_level"]), models=",".join(models),
                                     time_grid=time_grid, time_grid_description=grid_doc,
                                     time_interpolation="linear", **scene_attrs(cfg)))
    ds.attrs.update(attrs)
    ds.attrs["Conventions"] = "CF-1.8"
    ds.attrs["title"] = f"ureterfsi study: models {', '.join(models)}, mesh {ds.attrs['mesh_level']}"
    return ds


def scene_attrs(cfg: dict | None) -> dict:
    """The scenes (figures) of the configuration as dataset attributes: per scene its quantities, tolerance
    and the measured error of the rung the default runs use (config `scenes`, checked by `snakemake ladder`)."""
    scenes = (cfg or {}).get("scenes", {})
    return {"scenes": {name: {k: spec[k] for k in ("quantities", "tolerance", "measured_error") if k in spec}
                       for name, spec in scenes.items()}} if scenes else {}


def _select_probe_time(run: xr.Dataset, time: float, name: str = "stent_von_mises_line") -> xr.DataArray:
    pt = run["probe_time"].values.astype(float)
    i = int(np.argmin(np.abs(pt - time))) if pt.size else -1
    if i < 0 or abs(pt[i] - time) > 1e-6:
        raise BadFile(_source(run), f"run {run.attrs.get('model')}/{run.attrs.get('mesh_level')} has no probe at "
                                    f"t = {time} s (probe times {pt.tolist()})")
    return run[name].isel(probe_time=i)


def combine_levels(paths, time: float, cfg: dict | None = None) -> xr.Dataset:
    """Mesh-convergence dataset (paper §3.1, Fig. 3) of runs of one model on several mesh levels."""
    runs = _runs_by(paths, "mesh_level")
    models = {str(r.attrs["model"]) for r in runs.values()}
    if len(models) != 1:
        first = next(iter(runs.values()))
        odd = next(r for r in runs.values() if str(r.attrs["model"]) != str(first.attrs["model"]))
        raise BadFile(_source(odd), f"a run of model {odd.attrs['model']}, combined with model {first.attrs['model']} "
                                    f"({_source(first)}): a convergence study is one model on several meshes")
    order = list(cfg["mesh"]["levels"]) if cfg is not None else []
    levels = sorted(runs, key=lambda lv: (order.index(lv) if lv in order else len(order), lv))
    if "stent_von_mises_line" not in runs[levels[0]]:
        raise ValueError(f"model {models.pop()} has no stent: no von Mises probe line")
    z = runs[levels[0]]["z"].values
    line = np.vstack([_select_probe_time(runs[lv], time).values for lv in levels])

    def attr(lv, key):
        return float(runs[lv].attrs.get(key, np.nan))

    def peak(lv, name):
        """Maximum over [0, time]: the window every level covers (finer levels may stop at `time`)."""
        series = runs[lv][name]
        return float(series.where(series["time"] <= time + 1e-9).max())

    def outlet_hole(lv):
        """(peak |flux| over [0, time], peak |v_y| across it at `time`) of the outlet-most hole (+y side)."""
        run = runs[lv]
        k = int(np.flatnonzero((run["hole_z"].values == run["hole_z"].values.max()) & (run["hole_side"].values > 0))[0])
        flux = abs(run["hole_flux"].isel(hole=k))
        return (float(flux.where(flux["time"] <= time + 1e-9).max()),
                float(abs(_select_probe_time(run, time, "hole_velocity_y")).max()))

    ds = xr.Dataset(
        {"stent_von_mises_line": (("level", "z"), line),
         "cells": ("level", [attr(lv, "cells") for lv in levels]),
         "dofs": ("level", [attr(lv, "dofs") for lv in levels]),
         "processes": ("level", [attr(lv, "processes") for lv in levels]),
         "wall_time": ("level", [attr(lv, "wall_time_s") for lv in levels]),
         "peak_outlet_flux": ("level", [peak(lv, "outlet_flux") for lv in levels]),
         "peak_stent_max_von_mises": ("level", [peak(lv, "stent_max_von_mises") for lv in levels]),
         "peak_outlet_hole_flux": ("level", [outlet_hole(lv)[0] for lv in levels]),
         "outlet_hole_peak_velocity": ("level", [outlet_hole(lv)[1] for lv in levels])},
        coords={"level": ("level", np.array(levels, dtype=object)), "z": ("z", z)})
    ds["line_max_difference_to_finest"] = np.abs(ds["stent_von_mises_line"]
                                                 - ds["stent_von_mises_line"].isel(level=-1)).max("z")
    ds = annotate(ds)
    ds["stent_von_mises_line"].attrs["long_name"] = at_time(ds["stent_von_mises_line"].attrs["long_name"], time)
    attrs = {}
    for lv in levels:
        attrs.update(_run_attrs(lv, runs[lv].attrs))
        attrs[f"run_{lv}_source"] = Path(runs[lv].encoding["source"]).name
    model = models.pop()
    ds.attrs.update(provenance_attrs(cfg or {}, model=model, probe_time=float(time), levels=",".join(levels),
                                     **scene_attrs(cfg)))
    ds.attrs.update(attrs)
    ds.attrs["Conventions"] = "CF-1.8"
    ds.attrs["title"] = f"ureterfsi mesh convergence: model {model}, t = {time:g} s"
    return ds


def write_dataset(ds: xr.Dataset, path) -> None:
    """CF-1.8 netCDF output, atomically (ureterfsi.data.cf.write_netcdf)."""
    write_netcdf(ds, path)
