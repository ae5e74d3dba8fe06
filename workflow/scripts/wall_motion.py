"""Snakemake script of rule `wall_motion`: step 1 of the one-way rung, the ureter wall alone in r-z, shared
by every one-way run of the study (ureterfsi.oneway.write_wall_motion)."""
import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

from ureterfsi.oneway import write_wall_motion  # noqa: E402
from ureterfsi.study import configure_logging  # noqa: E402

with open(snakemake.log[0], "w") as log:  # noqa: F821
    configure_logging(log)
    write_wall_motion(snakemake.config, snakemake.output[0])  # noqa: F821
