"""Snakemake script of rule `calibration`: design-rule check and calibration of the wall (paper §2.4.2)."""
import logging

from ureterfsi.study.calibration import format_report, write_report
from ureterfsi.workflow.log import run_script

smk = snakemake  # noqa: F821


def main():
    report = write_report(dict(smk.params.sections), smk.output[0])   # geometry, ureter, peristalsis, time only
    logging.info("\n%s", format_report(report))


run_script(smk, main)
