"""Snakemake script of rule `design_rung_check`: a study's rung against the fully coupled model at its corners
(ureterfsi.designs.rung_check_dataset, ureterfsi.rung_check)."""
import logging

from ureterfsi.aggregate import write_dataset
from ureterfsi.designs import corner_run_paths, rung_check_dataset, studies

logging.basicConfig(filename=snakemake.log[0], level=logging.INFO)  # noqa: F821
name = snakemake.wildcards.design_study  # noqa: F821
ds = rung_check_dataset(snakemake.config, name, corner_run_paths(studies(snakemake.config)[name]))  # noqa: F821
write_dataset(ds, snakemake.output[0])  # noqa: F821
logging.info("design study %s: rung check -> %s: %s", name, snakemake.output[0], ds.attrs["rung_check"])  # noqa: F821
