"""Snakemake script of rule `design_wall_motion`: the r-z wall motion shared by the design points on one wall."""

from ureterfsi.designs.expand import wall_config
from ureterfsi.study.oneway import write_wall_motion
from ureterfsi.workflow.log import run_script

smk = snakemake  # noqa: F821
run_script(smk, lambda: write_wall_motion(wall_config(smk.config, smk.wildcards.wall_id), smk.output[0]))
