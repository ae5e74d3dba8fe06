"""Snakemake script of rule `design_rung_check`: a study's rung against the fully coupled model at its corners
(ureterfsi.design_results.rung_check_dataset, ureterfsi.rung_check)."""
import logging

from ureterfsi.aggregate import write_dataset
from ureterfsi.designs import corner_run_paths, studies
from ureterfsi.design_results import rung_check_dataset
from ureterfsi.workflow_log import run_script

smk = snakemake  # noqa: F821


def main():
    name = smk.wildcards.design_study
    ds = rung_check_dataset(smk.config, name, corner_run_paths(studies(smk.config)[name]))
    write_dataset(ds, smk.output[0])
    logging.info("design study %s: rung check -> %s: %s", name, smk.output[0], ds.attrs["rung_check"])


run_script(smk, main)
