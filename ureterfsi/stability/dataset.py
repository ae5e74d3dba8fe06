"""Datasets of the stability matrix: the per-case file, the combined matrix and its outcome table (no
dolfinx: read by the figures)."""
from __future__ import annotations

from dataclasses import dataclass, fields

import numpy as np
import xarray as xr

from ureterfsi.data.checked import Contract, open_netcdf
from ureterfsi.data.cf import annotate, write_netcdf
from ureterfsi.data.provenance import provenance_attrs
from .cases import SCENES

# time series of a case (StabilityObserver), one value per recorded state
SERIES = ("time", "dt", "kinetic_energy", "kinetic_energy_fluid", "kinetic_energy_solid", "elastic_energy",
          "energy_bound", "load_power", "open_boundary_power", "prescribed_power", "external_work", "fluid_volume",
          "volume_from_flux", "outlet_flux", "inlet_flux", "min_ale_jacobian", "max_displacement", "max_speed")
PER_STEP = tuple(k for k in SERIES if k != "time") + ("volume_balance_error", "newton_iterations",
                                                       "step_wall_time")


@dataclass(frozen=True)
class CaseScalars:
    """The per-case scalars of a case file (run_case), in the order written."""
    axis: str
    value_label: str
    outcome: str
    limit: str
    diagnosis: str
    failure_time: float
    failure_r: float
    failure_z: float
    pulse_centre_at_failure: float
    scene: str
    time_step: float
    mesh_level: str
    cells: int
    dofs: int
    hole_elements: float
    is_baseline: int
    hole_elements_measured: float
    hole_channels_found: int
    mesh_min_quality: float
    bulk_ratio: float
    density_ratio: float
    peak_traction: float
    wave_speed: float
    wave_width: float
    dynamic_viscosity: float
    end_time: float
    reached_time: float
    steps: int
    max_kinetic_energy: float
    max_energy_ratio: float
    displaced_volume: float
    volume_error: float
    min_jacobian: float
    peak_displacement: float
    peak_speed: float
    total_newton_iterations: int
    mean_newton_iterations: float
    max_newton_iterations: int
    step_halvings: int
    factorisations: int
    wall_time: float
    wall_time_per_step: float


SCALARS = tuple(f.name for f in fields(CaseScalars))
# what combine reads in a per-case file (run_case)
CASE_FILE = Contract("stability case file", attrs=("case",), variables=("case", "step", "time", "outcome"))


def write_case(ds: xr.Dataset, path) -> None:
    write_netcdf(ds, path)


def combine(items, cfg: dict | None = None) -> xr.Dataset:
    """Per-case datasets (or their paths) -> one dataset with dimension `case` (in the given order):
    every per-case scalar, and the time series padded with NaN along `step`."""
    runs = [it if isinstance(it, xr.Dataset) else open_netcdf(it, CASE_FILE) for it in items]
    if not runs:
        raise ValueError("no stability case to combine")
    names = [str(r["case"].values) for r in runs]
    nstep = max(r.sizes.get("step", 0) for r in runs)
    nhalv = max([r.sizes.get("halving", 0) for r in runs] + [0])
    scalar_names = [k for k, v in runs[0].data_vars.items() if v.ndim == 0]
    out = {}
    for k in scalar_names:
        vals = [r[k].values.item() for r in runs]
        out[k] = ("case", np.asarray(vals, dtype=object if isinstance(vals[0], str) else None))
    for k in ("time",) + PER_STEP:
        arr = np.full((len(runs), nstep), np.nan)
        for i, r in enumerate(runs):
            arr[i, : r.sizes["step"]] = r[k].values
        out[k] = (("case", "step"), arr)
    arr = np.full((len(runs), nhalv), np.nan)
    for i, r in enumerate(runs):
        if "halving_time" in r:
            arr[i, : r.sizes["halving"]] = r["halving_time"].values
    out["halving_time"] = (("case", "halving"), arr)
    ds = xr.Dataset(out, coords={"case": np.asarray(names, dtype=object), "step": np.arange(nstep)})
    annotate(ds)
    ds.attrs.update(provenance_attrs(cfg or {}, title="ureterfsi stability matrix",
                                     cases=",".join(names),
                                     scenes="; ".join(f"{k}: {v}" for k, v in SCENES.items()),
                                     energy_safety=runs[0].attrs.get("energy_safety", ""),
                                     volume_tolerance=runs[0].attrs.get("volume_tolerance", "")))
    for r, n in zip(runs, names):
        for key in ("config_hash", "git_commit", "created"):
            if key in r.attrs:
                ds.attrs[f"case_{n}_{key}"] = r.attrs[key]
    return ds


def outcome_table(ds: xr.Dataset) -> str:
    """Markdown table of the per-case outcomes of a combined dataset."""
    lines = ["| case | outcome | max E_kin (J) | E/bound | volume error | min J_ale | max \\|v\\| (mm/s) | halvings | "
             "Newton/step | steps | wall (s) | diagnosis |", "|" + "---|" * 12]
    for i, c in enumerate(ds["case"].values):
        d = ds.isel(case=i)
        lines.append(
            f"| {c} | {d['outcome'].item()} | {d['max_kinetic_energy'].item():.3g} | "
            f"{d['max_energy_ratio'].item():.2g} | {d['volume_error'].item():.2g} | "
            f"{d['min_jacobian'].item():.3f} | {1e3 * d['peak_speed'].item():.3g} | {int(d['step_halvings'].item())} | "
            f"{d['mean_newton_iterations'].item():.1f} | {int(d['steps'].item())} | {d['wall_time'].item():.1f} | "
            f"{d['diagnosis'].item()} |")
    return "\n".join(lines)
