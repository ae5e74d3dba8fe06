"""Snakemake script of rule `design_dataset`: the study's dataset from its points' runs and its rung check
(ureterfsi.designs)."""
import logging
from pathlib import Path

import xarray as xr

from ureterfsi.aggregate import write_dataset
from ureterfsi.designs import study_dataset

logging.basicConfig(filename=snakemake.log[0], level=logging.INFO)  # noqa: F821
name = snakemake.wildcards.design_study  # noqa: F821
paths = {Path(p).parent.name: p for p in snakemake.input.runs}  # noqa: F821
checked = "check" in snakemake.input.keys()  # noqa: F821
check = xr.load_dataset(snakemake.input.check, decode_times=False) if checked else None  # noqa: F821
ds = study_dataset(snakemake.config, name, paths, check)  # noqa: F821
write_dataset(ds, snakemake.output[0])  # noqa: F821
logging.info("design study %s: %d points -> %s; rung check: %s", name, len(paths), snakemake.output[0],  # noqa: F821
             ds.attrs["rung_check"])
