"""Snakemake script of rule `design_wall_motion`: the r-z wall motion shared by the design points on one wall."""
import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

from ureterfsi.designs import wall_config  # noqa: E402
from ureterfsi.study.oneway import write_wall_motion  # noqa: E402
from ureterfsi.study.cli import configure_logging  # noqa: E402

with open(snakemake.log[0], "w") as log:  # noqa: F821
    configure_logging(log)
    write_wall_motion(wall_config(snakemake.config, snakemake.wildcards.wall_id), snakemake.output[0])  # noqa: F821
