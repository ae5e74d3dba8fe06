"""Snakemake script of rule `design_rung_check`: a study's rung against the fully coupled model at its corners
(ureterfsi.designs.results.rung_check_dataset, ureterfsi.designs.rung_check)."""
import logging

from ureterfsi.analyses.aggregate import write_dataset
from ureterfsi.designs.expand import corner_run_paths, studies
from ureterfsi.designs.results import rung_check_dataset
from ureterfsi.workflow.log import run_script

smk = snakemake  # noqa: F821


def main():
    name = smk.wildcards.design_study
    ds = rung_check_dataset(smk.config, name, corner_run_paths(studies(smk.config)[name]))
    write_dataset(ds, smk.output[0])
    logging.info("design study %s: rung check -> %s: %s", name, smk.output[0], ds.attrs["rung_check"])


run_script(smk, main)
