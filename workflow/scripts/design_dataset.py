"""Snakemake script of rule `design_dataset`: the study's dataset from its points' runs (ureterfsi.designs)."""
import logging
from pathlib import Path

from ureterfsi.aggregate import write_dataset
from ureterfsi.designs import study_dataset
from ureterfsi.workflow_log import run_script

smk = snakemake  # noqa: F821


def main():
    name = smk.wildcards.design_study
    paths = {Path(p).parent.name: p for p in smk.input.runs}
    ds = study_dataset(smk.config, name, paths)
    write_dataset(ds, smk.output[0])
    logging.info("design study %s: %d points -> %s", name, len(paths), smk.output[0])


run_script(smk, main)
