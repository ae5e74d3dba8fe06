"""Snakemake script of rule `design_wall_motion`: the r-z wall motion shared by the design points on one wall."""
import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

from ureterfsi.designs import wall_config  # noqa: E402
from ureterfsi.study.oneway import write_wall_motion  # noqa: E402
from ureterfsi.workflow_log import run_script  # noqa: E402

smk = snakemake  # noqa: F821
run_script(smk, lambda: write_wall_motion(wall_config(smk.config, smk.wildcards.wall_id), smk.output[0]))
