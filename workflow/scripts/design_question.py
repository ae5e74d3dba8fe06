"""Snakemake script of rule `design_question` (ureterfsi.designs.question)."""
import logging

from ureterfsi.designs.question import write_table
from ureterfsi.workflow.log import run_script

smk = snakemake  # noqa: F821


def main():
    write_table(list(smk.input), smk.output[0])
    logging.info("design_question -> %s", smk.output[0])


run_script(smk, main)
