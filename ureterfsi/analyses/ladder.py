"""Fidelity ladder: what each cheaper model costs and what it loses against the reference.

Each rung is a run of the same stent model (config `ladder`): a fidelity (fully coupled / one-way), a
mesh symmetry, a mesh level and a time step. For every quantity behind a figure the error of a rung is
the relative max-norm error against the reference rung,

    e = max |q_rung - q_ref| / max |q_ref|,

over time (series, the rung interpolated linearly onto the reference times of the common span), over the
probe line /
hole section at every common probe time (snapshots), and over the side holes the two runs share
(a half model holds both holes of a pair, a quarter model one). Each scene (figure, config `scenes`)
declares its quantities and a tolerance; the scene's rung is the cheapest (wall time) whose largest
error over those quantities is within it.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np
import xarray as xr

from ureterfsi.data.checked import RUN_FILE, open_netcdf
from ureterfsi.data.cf import attach, ladder_variables
from ureterfsi.data.provenance import provenance_attrs

SERIES = ("outlet_flux", "inlet_flux", "outlet_mean_axial_velocity", "stent_max_von_mises",
          "max_wall_displacement", "hole_flux")
SNAPSHOTS = ("stent_von_mises_line", "wall_radial_displacement", "hole_velocity_y")
QUANTITIES = SERIES + SNAPSHOTS


def common_holes(ref: xr.Dataset, run: xr.Dataset):
    """Indices (ref, run) of the side holes present in both runs, matched by (z, side)."""
    key = lambda ds: [(round(float(z), 9), float(s)) for z, s in zip(ds["hole_z"].values, ds["hole_side"].values)]  # noqa: E731
    kr, kn = key(ref), key(run)
    pairs = [(i, kn.index(k)) for i, k in enumerate(kr) if k in kn]
    return [i for i, _ in pairs], [j for _, j in pairs]


def relative_error(ref: xr.Dataset, run: xr.Dataset, name: str) -> float:
    """Relative max-norm error of quantity `name` of `run` against `ref` (NaN if either lacks it)."""
    if name not in ref or name not in run:
        return float("nan")
    if name in SNAPSHOTS:
        times = [t for t in ref["probe_time"].values
                 if np.any(np.isclose(run["probe_time"].values, t, atol=1e-9))]
        if not times:
            return float("nan")
        a = np.stack([ref[name].sel(probe_time=t, method="nearest").values for t in times])
        b = np.stack([run[name].sel(probe_time=t, method="nearest").values for t in times])
    else:
        t_ref, t_run = ref["time"].values, run["time"].values
        keep = (t_ref >= t_run[0] - 1e-9) & (t_ref <= t_run[-1] + 1e-9)     # the common time span
        a = ref[name].values[..., keep]          # time last (CF §2.4)
        b = run[name].values
        if name == "hole_flux":
            i, j = common_holes(ref, run)
            a, b = a[i], b[j]
            b = np.stack([np.interp(t_ref[keep], t_run, bk) for bk in b])
        else:
            b = np.interp(t_ref[keep], t_run, b)
    scale = np.nanmax(np.abs(a))
    return float(np.nanmax(np.abs(b - a)) / scale) if scale > 0 else float(np.nanmax(np.abs(b - a)))


def select_rungs(error: xr.DataArray, cost: xr.DataArray, scenes: dict) -> dict:
    """{scene: (rung, error)}: the cheapest rung whose largest error over the scene's quantities is within
    its tolerance (the reference, error 0, always qualifies)."""
    out = {}
    order = [str(r) for r in cost.sortby(cost).rung.values]
    for scene, spec in scenes.items():
        qs = [q for q in spec["quantities"] if q in error["quantity"].values]
        worst = error.sel(quantity=qs).max("quantity", skipna=True) if qs else None
        choice = None
        for rung in order:
            e = float(worst.sel(rung=rung)) if worst is not None else float("nan")
            if np.isfinite(e) and e <= spec["tolerance"]:
                choice = (rung, e)
                break
        out[scene] = choice or ("none", float("nan"))
    return out


def default_rung(cfg: dict) -> str | None:
    """The ladder rung that the default study runs use (study.fidelity, mesh.symmetry, study.level, time.dt),
    or None if the ladder has no such rung."""
    own = {"fidelity": cfg["study"]["fidelity"], "symmetry": cfg["mesh"]["symmetry"],
           "level": cfg["study"]["level"], "dt": float(cfg["time"]["dt"])}
    for name, r in cfg["ladder"]["rungs"].items():
        if all((float(r[k]) if k == "dt" else r[k]) == v for k, v in own.items()):
            return name
    return None


def recorded_error_agrees(recorded: float, measured: float) -> bool:
    """A scene's recorded measured_error agrees with a new measurement to 10 % (or 1e-4 absolute)."""
    return bool(abs(measured - recorded) <= 0.1 * abs(recorded) + 1e-4)


def open_runs(paths: dict) -> dict:
    """{rung: run dataset} of `paths`, each checked as a run file."""
    return {name: open_netcdf(p, RUN_FILE) for name, p in paths.items()}


def ladder_dataset(paths: dict, cfg: dict, runs: dict | None = None) -> xr.Dataset:
    """Error of every rung against the reference for every quantity, with cost and the scene choices; `runs`: the
    run files of `paths` already opened (open_runs), else opened here."""
    lad = cfg["ladder"]
    runs = runs if runs is not None else open_runs(paths)
    ref = runs[lad["reference"]]
    names = list(runs)
    quantities = [q for q in QUANTITIES if q in ref]
    pairwise = np.array([[[relative_error(runs[a], runs[r], q) for q in quantities] for a in names] for r in names])
    error = pairwise[:, names.index(lad["reference"]), :]
    ds = xr.Dataset(
        {"error": (("rung", "quantity"), error),
         "pairwise_error": (("rung", "against", "quantity"), pairwise),
         "wall_time": ("rung", [float(runs[r].attrs["wall_time_s"]) for r in names]),
         "peak_memory": ("rung", [float(runs[r].attrs.get("peak_memory_mib", np.nan)) for r in names]),
         "cells": ("rung", [int(runs[r].attrs["cells"]) for r in names]),
         "dofs": ("rung", [int(runs[r].attrs["dofs"]) for r in names]),
         "time_step": ("rung", [float(lad["rungs"][r]["dt"]) for r in names]),
         "fidelity": ("rung", [lad["rungs"][r]["fidelity"] for r in names]),
         "symmetry": ("rung", [lad["rungs"][r]["symmetry"] for r in names]),
         "level": ("rung", [lad["rungs"][r]["level"] for r in names])},
        coords={"rung": ("rung", names), "against": ("against", names), "quantity": ("quantity", quantities)})
    scenes = cfg.get("scenes", {})
    default = None
    if scenes:
        chosen = select_rungs(ds["error"], ds["wall_time"], scenes)
        sc = list(scenes)
        ds = ds.assign_coords(scene=("scene", sc))
        ds["tolerance"] = ("scene", [float(scenes[s]["tolerance"]) for s in sc])
        ds["chosen_rung"] = ("scene", [chosen[s][0] for s in sc])
        ds["chosen_error"] = ("scene", [chosen[s][1] for s in sc])
        default = default_rung(cfg)
        if default is not None and default in names:
            ds.attrs["default_rung"] = default
            ds["default_error"] = ("scene", [float(ds["error"].sel(rung=default, quantity=[
                q for q in scenes[s]["quantities"] if q in quantities]).max(skipna=True)) for s in sc])
        ds["recorded_error"] = ("scene", [float(scenes[s].get("measured_error", np.nan)) for s in sc])
    attach(ds, ladder_variables(lad["reference"], default))
    ds.attrs.update(provenance_attrs(cfg, model=lad["model"], reference=lad["reference"], window_s=lad["end"]))
    for r in names:
        ds.attrs[f"run_{r}_source"] = Path(paths[r]).name
        for key in ("one_way_max_wall_pressure_deviation", "one_way_wall_pressure_mismatch",
                    "one_way_max_stent_displacement"):
            if key in runs[r].attrs:
                ds.attrs[f"run_{r}_{key}"] = float(runs[r].attrs[key])
    ds.attrs["Conventions"] = "CF-1.8"
    ds.attrs["title"] = f"ureterfsi fidelity ladder, model {lad['model']}, window {lad['end']:g} s"
    return ds


def ladder_table(ds: xr.Dataset) -> str:
    """Markdown table: per rung the cost and the error of each quantity; then the scene choices."""
    qs = [str(q) for q in ds["quantity"].values]
    head = "| rung | fidelity | symmetry | level | dt (s) | cells | wall time (s) | memory (MiB) | " + \
           " | ".join(qs) + " |"
    lines = [head, "|" + "---|" * (8 + len(qs))]
    for r in ds["rung"].values:
        row = ds.sel(rung=r)
        errs = " | ".join(f"{float(row['error'].sel(quantity=q)):.2e}" for q in qs)
        lines.append(f"| {r} | {row['fidelity'].item()} | {row['symmetry'].item()} | {row['level'].item()} | "
                     f"{float(row['time_step']):g} | {int(row['cells'])} | {float(row['wall_time']):.1f} | "
                     f"{float(row['peak_memory']):.0f} | {errs} |")
    if "scene" in ds.coords:
        default = ds.attrs.get("default_rung")
        lines += ["", f"| scene | tolerance | cheapest rung within it | its error | error of the default runs' rung "
                      f"({default or 'not in the ladder'}) | recorded in the config | check |",
                  "|---|---|---|---|---|---|---|"]
        for s in ds["scene"].values:
            row = ds.sel(scene=s)
            measured = float(row["default_error"]) if "default_error" in ds else float("nan")
            recorded = float(row["recorded_error"]) if "recorded_error" in ds else float("nan")
            checks = []
            if np.isfinite(measured):
                checks.append("within tolerance" if measured <= float(row["tolerance"]) else "EXCEEDS tolerance")
                if np.isfinite(recorded):
                    checks.append("matches" if recorded_error_agrees(recorded, measured) else "differs")
            lines.append(f"| {s} | {float(row['tolerance']):g} | {row['chosen_rung'].item()} | "
                         f"{float(row['chosen_error']):.2e} | {measured:.2e} | {recorded:.2e} | "
                         f"{', '.join(checks) or '-'} |")
    return "\n".join(lines) + "\n"
