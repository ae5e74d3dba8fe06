"""The results of a design study (ureterfsi.designs.space): each point's scalars from its run (peak and mean outlet flow,
backflow volume, hole exchange, stent lumen share, peak stent stress, wall displacement and pressure drop, the
stent's wall shear stress and the holes' gross exchange), the rung
check's dataset at the corners of the design space (the rung error per corner and quantity, ureterfsi.designs.rung_check),
the study's dataset (every point's parameters and scalars, per-point trust from the rung check) and its sensitivity
measures (standardised regression coefficients; first-order and total Sobol' indices, SALib.analyze.sobol).
"""
from __future__ import annotations

import json

import numpy as np
import xarray as xr

from ureterfsi.designs import jobs, rung_check as rc
from ureterfsi.data.checked import BadFile, Contract, open_netcdf
from ureterfsi.designs.expand import studies
from ureterfsi.designs.space import Study, base_values, point_id
from ureterfsi.designs.passage import (OBSTRUCTION_SERIES, escalated_points, lumen_share, obstruction_lumen_fraction,
                                       obstruction_variables, reference_variables, rung_variable, trapezoid)
from ureterfsi.mesh.geometry import SYMMETRY_FRACTION
from ureterfsi.data.cf import DESIGN_PARAMETERS, VARIABLES, reference_metadata, rung_check_metadata
from ureterfsi.data.provenance import provenance_attrs

# the stent's wall shear stress and the holes' gross exchange, copied from a run file (ureterfsi.study.stent_surface):
# per run, and per hole
STENT_SURFACE = tuple(f"stent_{r}_{k}" for r in ("outer", "lumen") for k in ("tawss", "osi", "low_wss_area_fraction"))
HOLE_SURFACE = ("hole_wall_tawss", "hole_wall_osi", "hole_wall_low_wss_area_fraction", "hole_gross_exchange_volume",
                "hole_net_volume", "hole_active")
PER_HOLE = ("peak_hole_flux", "hole_exchange_volume") + HOLE_SURFACE
# the end conditions' outcome (ureterfsi.study.end_probes): NaN for a run with the paper's open ends
END_CONDITIONS = ("peak_pelvic_pressure", "reflux_volume_lumen", "reflux_volume_annulus")
SCALARS = ("peak_outlet_flux", "mean_outlet_flux", "backflow_volume", "peak_hole_flux", "hole_exchange_volume",
           "hole_exchange_fraction", "stent_lumen_fraction", "peak_stent_von_mises", "peak_wall_displacement",
           "wall_time", "peak_pressure_drop", "mean_pressure_drop", "obstruction_lumen_fraction") + STENT_SURFACE + (
    HOLE_SURFACE + END_CONDITIONS)
QUANTITIES = ("peak_outlet_flux", "mean_outlet_flux", "backflow_volume", "hole_exchange_fraction",   # figures, indices
              "stent_lumen_fraction", "peak_stent_von_mises", "peak_wall_displacement", "peak_pressure_drop",
              "peak_pelvic_pressure", "obstruction_lumen_fraction")     # NaN with open ends / without an obstruction
SOBOL_INDICES = {"sobol_first_order": "S1", "sobol_first_order_conf": "S1_conf",   # dataset name: SALib's key
                 "sobol_total": "ST", "sobol_total_conf": "ST_conf"}
SERIES = ("outlet_flux", "inlet_flux", "outlet_lumen_flux", "stent_max_von_mises", "max_wall_displacement",
          "pressure_drop") + OBSTRUCTION_SERIES


def hole_mirror_weights(run) -> np.ndarray:
    """Per recorded hole, the holes of the full model it stands for: 2 where its opposite hole (same z and axis,
    other side) lies outside the symmetric model (its mirror image, the same flow), else 1."""
    if "hole_flux" not in run:
        return np.zeros(0)
    z, side = run["hole_z"].values, run["hole_side"].values
    axis = run["hole_axis"].values if "hole_axis" in run else np.ones_like(side)
    recorded = {(round(float(a), 9), int(b), float(c)) for a, b, c in zip(z, axis, side)}
    return np.array([1.0 if (round(float(a), 9), int(b), -float(c)) in recorded else 2.0
                     for a, b, c in zip(z, axis, side)])


def pressure_drop(run) -> np.ndarray:
    """p_in - p_out of a run dataset: inlet minus outlet area-mean end-face pressure (Pa; NaN where not recorded)."""
    if "inlet_mean_pressure" not in run:
        return np.full(run.sizes["time"], np.nan)
    return run["inlet_mean_pressure"].values.astype(float) - run["outlet_mean_pressure"].values.astype(float)


def pressure_drop_scalars(run) -> dict:
    """Peak |p_in - p_out| (the pulse drives the urine both ways, so a signed mean partly cancels) and its
    signed time mean (the net drop)."""
    t, dp = run["time"].values.astype(float), pressure_drop(run)
    return {"peak_pressure_drop": float(np.max(np.abs(dp))), "mean_pressure_drop": trapezoid(dp, t) / (t[-1] - t[0])}


def end_condition_scalars(run) -> dict:
    """The peak renal pelvis pressure and the urine moved toward the kidney over the run, inside the stent lumen and
    outside it (the reflux volumes' last values: they accumulate from t = 0); NaN where the run has no such record."""
    def last(name):
        return float(run[name].values[-1]) if name in run else np.nan

    return {"peak_pelvic_pressure": float(np.max(run["pelvic_pressure"].values)) if "pelvic_pressure" in run else np.nan,
            "reflux_volume_lumen": last("stent_lumen_reflux_volume"),
            "reflux_volume_annulus": last("annulus_reflux_volume")}


def point_scalars(run) -> dict:
    """The scalars of one run dataset (ureterfsi.study.probes.probes_dataset); hole flows per hole."""
    t = run["time"].values.astype(float)
    q = run["outlet_flux"].values.astype(float)
    hole = run["hole_flux"].values.astype(float) if "hole_flux" in run else np.zeros((0, t.size))   # (hole, time)
    mirror = hole_mirror_weights(run)
    exchange = np.array([trapezoid(np.abs(h), t) for h in hole])
    lumen_fraction = (lumen_share(q, run["outlet_lumen_flux"].values.astype(float), t) if "outlet_lumen_flux" in run
                      else np.nan)
    return {"peak_outlet_flux": float(q.max()), "mean_outlet_flux": trapezoid(q, t) / (t[-1] - t[0]),
            "backflow_volume": trapezoid(np.maximum(-q, 0.0), t),
            "peak_hole_flux": np.abs(hole).max(axis=1) if hole.size else np.zeros(0),
            "hole_exchange_volume": exchange,
            "hole_exchange_fraction": float(np.sum(mirror * exchange)) / trapezoid(np.abs(q), t),
            "stent_lumen_fraction": lumen_fraction, "obstruction_lumen_fraction": obstruction_lumen_fraction(run),
            "peak_stent_von_mises": float(run["stent_max_von_mises"].max()) if "stent_max_von_mises" in run else np.nan,
            "peak_wall_displacement": float(run["max_wall_displacement"].max()),
            "wall_time": float(run.attrs.get("wall_time_s", np.nan))} | pressure_drop_scalars(run) | {
        k: float(run[k]) if k in run else np.nan for k in STENT_SURFACE} | {
        k: run[k].values.astype(float) if k in run else np.full(hole.shape[0], np.nan) for k in HOLE_SURFACE} | (
        end_condition_scalars(run))


def mesh_motion_variables(points, runs) -> dict:
    """Per point (on the one-way rung): the ALE map its urine solve used (solver.one_way_mesh_motion, resolved under
    auto), the algebraic map's and the extension's predicted minimum Jacobians (auto, the extension's where the
    algebraic one is below the limit; NaN otherwise) and the run's minimum Jacobian."""
    def attr(p, key, default):
        return runs[p.id].attrs.get(key, default)

    return {"mesh_motion": (("design",), np.array([str(attr(p, "one_way_mesh_motion", "")) for p in points], dtype=object)),
            "predicted_min_jacobian": (("design",), np.array([float(attr(p, "one_way_predicted_min_jacobian", np.nan))
                                                              for p in points])),
            "predicted_extension_min_jacobian": (("design",), np.array(
                [float(attr(p, "one_way_predicted_extension_min_jacobian", np.nan)) for p in points])),
            "min_ale_jacobian": (("design",), np.array([float(runs[p.id]["min_ale_jacobian"].min()) for p in points]))}


# what study_dataset (point_scalars, mesh_motion_variables) relies on in a point's run file (a run file,
# checked_io.RUN_FILE, of which it reads these)
DESIGN_RUN = Contract("run file", variables=("time", "outlet_flux", "max_wall_displacement", "min_ale_jacobian"),
                      units=VARIABLES)
# what the design figures (ureterfsi.plotting.designs, workflow/scripts/design_figures.py) rely on in a study's dataset
DESIGN_DATASET = Contract("design-study dataset", attrs=("study", "design_kind", "model", "points"))
# what study_dataset takes from a study's rung check (rung_check_dataset)
RUNG_CHECK = Contract("rung check", attrs=("rung_check",),
                      variables=("rung_error", "max_rung_error", "rung_tolerance", "corner_within_tolerance"))


def read_run(path) -> xr.Dataset:
    """A design solve's run file (a point's, a reference's or a corner's), checked: a run (DESIGN_RUN), or the record
    of a solve that failed (attribute solve_failed, ureterfsi.study.run.write_failed_run)."""
    ds = open_netcdf(path, Contract("design run file"))
    return ds if "solve_failed" in ds.attrs else open_netcdf(path, DESIGN_RUN)


def rung_check_summary(st: Study, error: np.ndarray, inside: list | None, failed: dict | None = None) -> str:
    """One paragraph on the study's rung check (the dataset's attribute rung_check, the figures' captions): what
    was checked, the largest error against the tolerance, the corners beyond it, those whose solve failed
    (`failed`: corner id -> message) and (unless `inside` is None) the points outside the checked region (or that
    there are none)."""
    ch = st.check
    if ch is None:
        return (f"not checked: the study's rung is {st.rung}" if st.rung == rc.REFERENCE_RUNG else
                f"not checked (design_studies.{st.name}.rung_check.corners: none): the {st.rung} rung's error at "
                f"these designs is not measured")
    where = "the study's own segment" if ch.on_segment else f"the segment {ch.segment}"
    worst = float(np.nanmax(error)) if np.isfinite(error).any() else np.nan
    text = (f"{st.rung} checked against {rc.REFERENCE_RUNG} ({rc.REFERENCE_SCHEME}) at {len(ch.corners)} corners "
            f"({ch.mode}) of the design space on {where}: largest relative error {worst:.2g} "
            f"(tolerance {ch.tolerance:g})")
    failed = failed or {}
    bad = [c.id for c, e in zip(ch.corners, error) if c.id not in failed and not np.nanmax(e, initial=0.0) <= ch.tolerance]
    unmeasured = [c.id for c, e in zip(ch.corners, error) if c.id not in failed and not np.isfinite(e).any()]
    text += (f"; corners beyond the tolerance: {', '.join(bad)}" if bad else
             "; every corner solved within it" if failed else "; every corner within it")
    if unmeasured:
        text += f" (no finite error at {', '.join(unmeasured)})"
    if failed:
        text += "; not checked (a solve failed) at " + "; ".join(f"{k}: {v}" for k, v in failed.items())
    if inside is None:
        return text
    out = [p.id for p, i in zip(st.points, inside) if not i]
    text += (f"; {len(out)} of {len(st.points)} design points outside the checked region: {', '.join(out)}" if out
             else "; every design point inside the checked region")
    return text


def error_scales(run) -> dict:
    """The scales of the outlet-flow scalars of a (fully coupled) run for their rung errors (ureterfsi.designs.rung_check):
    max |Q_out| for the peak and the mean outlet flow, integral |Q_out| dt for the backflow volume."""
    t, q = run["time"].values.astype(float), run["outlet_flux"].values.astype(float)
    peak = float(np.max(np.abs(q)))
    return {"peak_outlet_flux": peak, "mean_outlet_flux": peak, "backflow_volume": trapezoid(np.abs(q), t)}


def rung_check_dataset(cfg: dict, name: str, corner_paths: dict) -> xr.Dataset:
    """The rung check of study `name` (ureterfsi.designs.rung_check) from its corners' run files {corner id: (run on the
    study's rung, fully coupled run)}: per corner and quantity the relative error, its maximum over the corners,
    the tolerance, per corner whether it is within it and both solves' wall times, the corners' parameter values;
    the attribute rung_check says what was checked and what is outside (rung_check_summary). CF-annotated
    (ureterfsi.data.cf.rung_check_metadata)."""
    st = studies(cfg)[name]
    ch = st.check
    if ch is None:
        raise ValueError(f"design study {name} has no rung check (design_studies.{name}.rung_check.corners: none)")
    error, wall = np.full((len(ch.corners), len(QUANTITIES)), np.nan), np.full((len(ch.corners), 2), np.nan)
    failed = {}
    for i, c in enumerate(ch.corners):
        runs = [read_run(path) for path in corner_paths[c.id]]
        for path, run, rung in zip(corner_paths[c.id], runs, (st.rung, rc.REFERENCE_RUNG)):
            refuse_other_configuration(path, run, jobs.corner_config_hash(st, c.id, rung),
                                       f"rung-check corner {st.name}/{c.id}'s on the {rung} rung")
        failed.update({c.id: r.attrs["solve_failed"] for r in runs if "solve_failed" in r.attrs})
        if c.id in failed:
            continue
        rung, ref = (point_scalars(r) for r in runs)
        error[i] = rc.relative_errors(rung, ref, QUANTITIES, error_scales(runs[1]))
        wall[i] = [float(r.attrs.get("wall_time_s", np.nan)) for r in runs]
    corner_ok = np.array([c.id not in failed and np.nanmax(e, initial=0.0) <= ch.tolerance
                          for c, e in zip(ch.corners, error)])
    measured = np.isfinite(error).any(axis=0)
    worst = np.where(measured, np.nanmax(np.where(np.isfinite(error), error, -np.inf), axis=0), np.nan)
    ds = xr.Dataset({"rung_error": (("corner", "quantity"), error),
                     "max_rung_error": (("quantity",), worst),
                     "corner_within_tolerance": (("corner",), corner_ok.astype(np.int8)),
                     "corner_rung_wall_time": (("corner",), wall[:, 0]),
                     "corner_reference_wall_time": (("corner",), wall[:, 1]),
                     "rung_tolerance": ((), ch.tolerance)},
                    coords={"corner": ("corner", [c.id for c in ch.corners]),
                            "quantity": ("quantity", list(QUANTITIES)),
                            **{f"corner_{q}": ("corner", [c.values[q] for c in ch.corners]) for q in st.parameters}})
    meta = rung_check_metadata(st.parameters) | {"quantity": VARIABLES["quantity"]}
    for k in ds.variables:
        ds[k].attrs.update(units=meta[k][0], long_name=meta[k][1])
    attrs = {"rung_check": rung_check_summary(st, error, None, failed), "rung_check_corners": ch.mode,
             "rung_check_tolerance": ch.tolerance, "rung_check_segment": ch.segment,
             "rung_check_max_error": float(np.nanmax(error)) if np.isfinite(error).any() else np.nan,
             "rung_check_rung": st.rung, "rung_check_reference": f"{rc.REFERENCE_RUNG} ({rc.REFERENCE_SCHEME})",
             "rung_check_reused_points": ch.reuses, "rung_check_failed_corners": failed,
             "rung_check_corners_beyond_tolerance": [c.id for c, k in zip(ch.corners, corner_ok) if not k]}
    ds.attrs.update(provenance_attrs(cfg, study=name, model=st.model, mesh_level=st.level,
                                     corners={c.id: c.values for c in ch.corners},
                                     corner_symmetry={c.id: c.symmetry for c in ch.corners}))
    ds.attrs.update({k: v if isinstance(v, (int, float, str)) else json.dumps(v) for k, v in attrs.items()})
    ds.attrs["Conventions"] = "CF-1.8"
    ds.attrs["title"] = f"ureterfsi design study {name}: {st.rung} against {rc.REFERENCE_RUNG} at the corners"
    return ds


RUNG_CHECK_COPIED = ("rung_error", "max_rung_error", "corner_within_tolerance", "corner_rung_wall_time",
                     "corner_reference_wall_time", "rung_tolerance")


def _rung_check_part(st: Study, check) -> tuple[xr.Dataset | None, dict, np.ndarray, np.ndarray]:
    """(the check's variables, its attributes, per point: inside the checked region, trusted) for study_dataset."""
    inside = np.array([st.check.inside(p.values) if st.check else False for p in st.points])
    if check is None:
        if st.check is not None:
            raise ValueError(f"design study {st.name} is checked at its corners: pass its rung check dataset")
        return None, {"rung_check": rung_check_summary(st, np.zeros((0, len(QUANTITIES))), list(inside))}, \
            inside.astype(np.int8), np.zeros(len(st.points), np.int8)
    all_ok = bool(np.asarray(check["corner_within_tolerance"].values).all())
    part = check[list(RUNG_CHECK_COPIED)]
    attrs = {k: v for k, v in check.attrs.items() if k.startswith("rung_check")}
    failed = json.loads(check.attrs.get("rung_check_failed_corners", "{}"))
    attrs["rung_check"] = rung_check_summary(st, check["rung_error"].values, list(inside), failed)   # with the points
    attrs["rung_check_outside_points"] = json.dumps([p.id for p, i in zip(st.points, inside) if not i])
    return part, attrs, inside.astype(np.int8), (inside & all_ok).astype(np.int8)


def read_point_run(st: Study, point_id: str, path) -> xr.Dataset:
    """A point's (or reference's) run file (DESIGN_RUN), refused (BadFile) unless it was made under the configuration
    the point's solve on the run's rung is given now (its config_hash, jobs.solve_config_hash): a run kept from an
    earlier version of the study (Snakemake told to rerun on mtime alone) is not mixed into the dataset."""
    run = open_netcdf(path, DESIGN_RUN)
    rung = run.attrs.get("fidelity") or run.attrs.get("rung")
    refuse_other_configuration(path, run, jobs.solve_config_hash(st, point_id, rung),
                               f"design point {st.name}/{point_id}'s on the {rung} rung")
    return run


def refuse_other_configuration(path, run: xr.Dataset, want: str, whose: str) -> None:
    """BadFile (one line, naming `path`) unless the run file `run` records the config_hash `want` of `whose`
    solve's configuration."""
    got = run.attrs.get("config_hash")
    if got != want:
        raise BadFile(path, f"made under another configuration than {whose} (config_hash {got!r}, the solve's now "
                            f"{want!r}): re-run it (snakemake --forcerun {path})")


def study_dataset(cfg: dict, name: str, paths: dict, check: xr.Dataset | None = None):
    """Dataset of a study from its run files {point id: path} and, for a checked study, its rung check
    (rung_check_dataset), whose variables and attributes it takes, with per point whether it lies in the checked
    region and whether it is trusted there (see the module docstring and ureterfsi.designs.rung_check)."""
    st = studies(cfg)[name]
    runs = {p.id: read_point_run(st, p.id, paths[p.id]) for p in st.points}
    references = {r.id: point_scalars(read_point_run(st, r.id, paths[r.id])) for r in st.references}
    tc = cfg["time"]
    t = np.round(np.arange(0.0, tc["end"] + 0.5 * tc["dt"], tc["dt"]), 9)
    n_hole = max(r.sizes.get("hole", 0) for r in runs.values())
    n = len(st.points)
    data = {k: np.full((n, n_hole) if k in PER_HOLE else n, np.nan) for k in SCALARS}
    series = {k: np.full((n, t.size), np.nan) for k in SERIES}
    hole_series, hole_z = np.full((n, n_hole, t.size), np.nan), np.full((n, n_hole), np.nan)
    hole_axis, hole_side = np.full((n, n_hole), np.nan), np.full((n, n_hole), np.nan)
    for i, p in enumerate(st.points):
        r = runs[p.id]
        for k, v in point_scalars(r).items():
            data[k][i, ...] = v if np.ndim(v) == 0 else np.pad(v, (0, n_hole - len(v)), constant_values=np.nan)
        rt = np.round(r["time"].values.astype(float), 9)     # the grid's rounding: summed steps end at 2.99999999999998
        for k in SERIES:
            if k in r or k == "pressure_drop":
                v = pressure_drop(r) if k == "pressure_drop" else r[k].values
                series[k][i] = np.interp(t, rt, v, left=np.nan, right=np.nan)
        for j in range(r.sizes.get("hole", 0)):
            hole_series[i, j] = np.interp(t, rt, r["hole_flux"].values[j], left=np.nan, right=np.nan)
            hole_z[i, j] = float(r["hole_z"].values[j])
            hole_side[i, j] = float(r["hole_side"].values[j])
            hole_axis[i, j] = float(r["hole_axis"].values[j]) if "hole_axis" in r else 1.0
    vars_ = {k: (("design", "hole") if v.ndim == 2 else ("design",), v) for k, v in data.items()}
    vars_ |= {k: (("design", "time"), v) for k, v in series.items()}
    vars_["hole_flux"] = (("design", "hole", "time"), hole_series)
    vars_["model_fraction"] = (("design",), np.array([SYMMETRY_FRACTION[p.symmetry] for p in st.points]))
    vars_ |= mesh_motion_variables(st.points, runs)
    check_part, check_attrs, inside, trusted = _rung_check_part(st, check)
    vars_["in_rung_check_region"] = (("design",), inside)
    vars_["rung_trusted"] = (("design",), trusted)
    escalated = escalated_points(st, check["corner_within_tolerance"].values) if check is not None else []
    vars_ |= rung_variable(st, escalated)
    passage, passage_coords = obstruction_variables(st.points, hole_z)
    vars_ |= passage
    coords = {"design": ("design", [p.id for p in st.points]), "time": ("time", t), "hole": ("hole", np.arange(n_hole)),
              "hole_z": (("design", "hole"), hole_z), "hole_side": (("design", "hole"), hole_side),
              "hole_axis": (("design", "hole"), hole_axis)} | passage_coords
    coords |= {q: ("design", [p.values[q] for p in st.points]) for q in st.parameters}
    ds = xr.Dataset(vars_, coords=coords)
    if check_part is not None:
        ds = ds.merge(check_part)
    ref_vars, ref_coords = reference_variables(st, references)
    ds = ds.assign(ref_vars).assign_coords(ref_coords)
    meta = (VARIABLES | {q: DESIGN_PARAMETERS[q] for q in st.parameters} | rung_check_metadata(st.parameters)
            | reference_metadata(q.removeprefix("reference_") for q in ref_vars))
    if st.kind == "full_factorial":
        if len(st.parameters) == 1:   # one parameter: a plain index, nothing to unstack
            ds = ds.swap_dims(design=st.parameters[0]).drop_vars("design")
        else:
            ds = ds.set_index(design=st.parameters).unstack("design")
        ds = ds.reindex({q: st.grid[q] for q in st.parameters}).transpose(*st.parameters, ...)
        ds["point_id"] = xr.DataArray(np.array([p.id for p in st.points], dtype=object).reshape(
            [len(st.grid[q]) for q in st.parameters]), dims=st.parameters)
    if st.rows:
        index = {p.id: i for i, p in enumerate(st.points)}
        ds["saltelli_point"] = ("saltelli_row", np.array([index[r] for r in st.rows], dtype=np.int32))
        ds = add_sobol_indices(ds, st.parameters, cfg["design_studies"][name]["sample"]["seed"])
    for k in ds.variables:
        if k in meta:
            ds[k].attrs.update(units=meta[k][0], long_name=meta[k][1])
    ds.attrs.update(provenance_attrs(cfg, study=name, design_kind=st.kind, model=st.model, mesh_level=st.level,
                                     rung=st.rung, escalated_points=escalated,
                                     point_symmetry={p.id: p.symmetry for p in st.points},
                                     base_values=st.base,
                                     study_base=cfg["design_studies"][name].get("base") or {},
                                     points={p.id: p.values for p in st.points},
                                     point_config_hashes={p.id: runs[p.id].attrs.get("config_hash", "") for p in st.points},
                                     references={r.name: r.id for r in st.references}))
    ds.attrs.update({k: v if isinstance(v, (int, float, str)) else json.dumps(v) for k, v in check_attrs.items()})
    ds.attrs["Conventions"] = "CF-1.8"
    ds.attrs["title"] = f"ureterfsi design study {name}: model {st.model}, {st.kind}, {len(st.points)} points"
    return ds


def standardised_regression_coefficients(ds, parameters, quantity: str) -> tuple[np.ndarray, float]:
    """SRC_j = b_j s_xj / s_y of the least-squares fit y = b0 + sum b_j x_j over the points of `ds` (one point
    dimension), and its R^2."""
    X = np.column_stack([np.asarray(ds[q].values, float) for q in parameters])
    y = np.asarray(ds[quantity].values, float)
    ok = np.isfinite(y)
    X, y = X[ok], y[ok]
    Xs = (X - X.mean(0)) / np.where(X.std(0) > 0, X.std(0), 1.0)
    ys = (y - y.mean()) / (y.std() if y.std() > 0 else 1.0)
    beta, *_ = np.linalg.lstsq(np.c_[np.ones(len(ys)), Xs], ys, rcond=None)
    r2 = 1.0 - float(np.sum((ys - np.c_[np.ones(len(ys)), Xs] @ beta) ** 2)) / max(float(np.sum(ys ** 2)), 1e-300)
    return beta[1:], r2


def sobol_indices(ds, parameters, quantity: str, seed: int = 0) -> dict:
    """First-order and total Sobol' indices S1_j = V[E(y | x_j)] / V(y), ST_j = E[V(y | x_~j)] / V(y) of `quantity`
    over a Saltelli design (y of sample row r: the point saltelli_point[r]; `parameters` in the sample's column
    order), with the half-widths of their 95 % bootstrap confidence intervals (SALib.analyze.sobol); NaN where a
    point has no value or y is constant. Keys: SOBOL_INDICES."""
    from SALib.analyze import sobol

    y = np.asarray(ds[quantity].values, float)[np.asarray(ds["saltelli_point"].values, int)]
    if not np.isfinite(y).all() or np.ptp(y) == 0:
        return {k: np.full(len(parameters), np.nan) for k in SOBOL_INDICES}
    problem = {"num_vars": len(parameters), "names": list(parameters), "bounds": [[0.0, 1.0]] * len(parameters)}
    res = sobol.analyze(problem, y, calc_second_order=True, conf_level=0.95, seed=seed)
    return {k: np.asarray(res[v], float) for k, v in SOBOL_INDICES.items()}


def add_sobol_indices(ds, parameters, seed: int = 0, quantities=QUANTITIES):
    """`ds` with the Sobol' indices (sobol_indices) of each of `quantities` it holds, on (quantity, parameter)."""
    qs = [q for q in quantities if q in ds]
    res = [sobol_indices(ds, parameters, q, seed) for q in qs]
    data = {k: (("quantity", "parameter"), np.array([r[k] for r in res], float).reshape(len(qs), len(parameters)))
            for k in SOBOL_INDICES}
    return ds.assign(data).assign_coords(quantity=("quantity", qs), parameter=("parameter", list(parameters)))
