"""Snakemake script of rule `design_solve`: one design point on its study's rung (ureterfsi.designs.solve_point)."""
import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

from ureterfsi.designs import solve_point, studies  # noqa: E402
from ureterfsi.study import configure_logging  # noqa: E402

w = snakemake.wildcards  # noqa: F821
study = studies(snakemake.config)[w.design_study]  # noqa: F821
with open(snakemake.log[0], "w") as log:  # noqa: F821
    configure_logging(log)
    solve_point(snakemake.config, study, study.point(w.point), snakemake.input.mesh, snakemake.output[0],  # noqa: F821
                snakemake.params.checkpoint, snakemake.input.get("wall"))  # noqa: F821
