"""One study run on a rung of the fidelity ladder: what every command line and workflow script that solves calls."""
from __future__ import annotations

import xarray as xr

from ureterfsi.study import coupled, oneway
from ureterfsi.study.options import RunSpec


def solve(cfg: dict, spec: RunSpec, fidelity: str, out_path: str, checkpoint_path: str | None = None,
          wall_path: str | None = None) -> xr.Dataset:
    """One run on rung `fidelity` (FIDELITIES); the one-way rung reads the wall motion `wall_path` if given."""
    if fidelity == "one_way":
        return oneway.run(cfg, spec, out_path, checkpoint_path, wall_path=wall_path)
    return coupled.run(cfg, spec, out_path, checkpoint_path)
