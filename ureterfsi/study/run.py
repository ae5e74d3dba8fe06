"""One study run on a rung of the fidelity ladder: what every command line and workflow script that solves calls."""
from __future__ import annotations

import xarray as xr

from ureterfsi.data.cf import write_netcdf
from ureterfsi.data.provenance import provenance_attrs
from ureterfsi.study import coupled, oneway
from ureterfsi.study.options import RunSpec


def solve(cfg: dict, spec: RunSpec, fidelity: str, out_path: str, checkpoint_path: str | None = None,
          wall_path: str | None = None) -> xr.Dataset:
    """One run on rung `fidelity` (FIDELITIES); the one-way rung reads the wall motion `wall_path` if given."""
    if fidelity == "one_way":
        return oneway.run(cfg, spec, out_path, checkpoint_path, wall_path=wall_path)
    return coupled.run(cfg, spec, out_path, checkpoint_path)


def write_failed_run(cfg: dict, path, rung: str, message: str) -> None:
    """The run file of a solve on `rung` that failed: no data, the failure in its attribute solve_failed (a
    rung-check corner's, which ureterfsi.designs.results.rung_check_dataset reports as not checked)."""
    ds = xr.Dataset(attrs=provenance_attrs(cfg, rung=rung, solve_failed=message))
    write_netcdf(ds, path, title=f"ureterfsi run: the {rung} solve failed")
