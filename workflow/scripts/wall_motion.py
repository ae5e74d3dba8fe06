"""Snakemake script of rule `wall_motion`: step 1 of the one-way rung, the ureter wall alone in r-z, shared
by every one-way run of the study (ureterfsi.study.oneway.write_wall_motion)."""

from ureterfsi.study.oneway import write_wall_motion
from ureterfsi.workflow.log import run_script

smk = snakemake  # noqa: F821
run_script(smk, lambda: write_wall_motion(smk.config, smk.output[0]))
