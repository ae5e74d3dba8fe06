"""Design studies run by Snakemake from the tests: a dry run's job counts, and a study's outputs made to look
done (for what a change re-runs)."""
from __future__ import annotations

import copy
import os
from pathlib import Path

import numpy as np
import xarray as xr
import yaml

from ureterfsi.config import load_config
from ureterfsi.data import cf as metadata
from ureterfsi.data.provenance import FORMAT_VERSION, FORMAT_VERSION_ATTR
from ureterfsi.designs.expand import corner_run_paths, design_figure_kinds, studies
from helpers.snakemake_runs import job_counts, ok, snakemake


def grid(mode="full_factorial", model="3", **params):
    """A study entry of design_studies: `params` varied as a grid (`mode`) on the coarse level of `model`."""
    return {"model": model, "level": "coarse", "grid": {"mode": mode, "parameters": params}}


def fake_run(path: Path, peak: float, disp: float, wall_time: float = 1.0) -> None:
    """A run file with what point_scalars reads: an outlet flow peaking at `peak`, a wall displacement `disp`."""
    t = np.linspace(0.0, 0.04, 3)
    ds = xr.Dataset({"outlet_flux": ("time", peak * np.array([0.0, 1.0, 0.5])),
                     "max_wall_displacement": ("time", disp * np.array([0.0, 0.5, 1.0])),
                     "min_ale_jacobian": ("time", np.array([1.0, 0.9, 0.8]))},
                    coords={"time": ("time", t)}, attrs={"wall_time_s": wall_time, "config_hash": "x"})
    # as the run writer marks it (the rung check reads run files through checked_io: format version and units)
    metadata.annotate(ds)
    ds.attrs[FORMAT_VERSION_ATTR] = FORMAT_VERSION
    ds.to_netcdf(path)


def stamp(st, paths: dict) -> dict:
    """Mark the synthetic run files {point or reference id: path} of study `st` as its solves write them: the rung
    (fidelity; a point's fully_coupled.nc the escalated run's) and the config_hash of the configuration that solve is
    given (ureterfsi.designs.jobs.solve_config_hash), which the study's dataset checks. Returns `paths`."""
    from ureterfsi.designs import jobs

    for pid, path in paths.items():
        rung = "fully_coupled" if Path(path).name == "fully_coupled.nc" else st.point(pid).rung
        _set_attrs(path, fidelity=rung, config_hash=jobs.solve_config_hash(st, pid, rung))
    return paths


def stamp_corners(st, corners: dict) -> dict:
    """The same for the rung check's corner runs {corner id: (run on the study's rung, fully coupled run)}
    (ureterfsi.designs.jobs.corner_config_hash). Returns `corners`."""
    from ureterfsi.designs import jobs

    for cid, pair in corners.items():
        for path, rung in zip(pair, (st.rung, "fully_coupled")):
            _set_attrs(path, config_hash=jobs.corner_config_hash(st, cid, rung))
    return corners


def _set_attrs(path, **attrs) -> None:
    import netCDF4

    with netCDF4.Dataset(path, "a") as nc:
        for k, v in attrs.items():
            nc.setncattr(k, v)


def dry_run(work: Path, cfg: dict, target: str, *args):
    """The job counts {rule: n} of a dry run of `target` with configuration `cfg` (written to work/cfg.yaml)."""
    path = work / "cfg.yaml"
    path.write_text(yaml.safe_dump(cfg, sort_keys=False))
    return job_counts(ok(snakemake(work, path, "-n", target, *args, profile=None)))


def pretend_done(work: Path, cfg: dict, name: str) -> None:
    """Every output of study `name` (points and, with a rung check, corners) as an empty file, in job order (then
    `snakemake --touch` records them as made by their jobs)."""
    st = studies(load_config(copy.deepcopy(cfg)))[name]
    every = st.points + (st.check.corners if st.check else [])
    runs = [f for pair in corner_run_paths(st).values() for f in pair] if st.check else []
    stages = [[f"results/designs/meshes/{p.mesh_id}.{e}" for p in every for e in ("msh", "json")]
              + [f"results/designs/wall_motion/{p.wall_id}.nc" for p in every],
              [f"results/designs/{name}/{p.id}/run.nc" for p in st.points] + runs,
              [f"results/designs/{name}/rung_check.nc"] if st.check else [], [f"results/designs/{name}.nc"],
              [f"results/figures/designs/{name}_{k}.{e}" for k in design_figure_kinds(st)
               for e in cfg["figures"]["formats"]]]
    for i, stage in enumerate(stages):
        for f in stage:
            (work / f).parent.mkdir(parents=True, exist_ok=True)
            (work / f).touch()
            os.utime(work / f, (1e9 + i, 1e9 + i))
