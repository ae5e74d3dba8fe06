"""Snakemake script of rule `design_dataset`: the study's dataset from its points' runs and its rung check
(ureterfsi.designs.results)."""
import logging
from pathlib import Path

from ureterfsi.analyses.aggregate import write_dataset
from ureterfsi.data.checked import open_netcdf
from ureterfsi.designs.results import RUNG_CHECK, study_dataset
from ureterfsi.workflow.log import run_script

smk = snakemake  # noqa: F821


def main():
    name = smk.wildcards.design_study
    paths = {Path(p).parent.name: p for p in smk.input.runs}
    check = open_netcdf(smk.input.check, RUNG_CHECK) if "check" in smk.input.keys() else None
    ds = study_dataset(smk.config, name, paths, check)
    write_dataset(ds, smk.output[0])
    logging.info("design study %s: %d points -> %s; rung check: %s", name, len(paths), smk.output[0],
                 ds.attrs["rung_check"])


run_script(smk, main)
