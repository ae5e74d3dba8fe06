"""Snakemake script of rule `design_solve`: one design point on its study's rung (ureterfsi.study.cli.solve)."""
import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

from ureterfsi.designs import studies  # noqa: E402
from ureterfsi.study.cli import configure_logging, solve  # noqa: E402
from ureterfsi.study.oneway import MeshMotionRefused  # noqa: E402
from ureterfsi.study.options import RunSpec  # noqa: E402

w = snakemake.wildcards  # noqa: F821
study = studies(snakemake.config)[w.design_study]  # noqa: F821
with open(snakemake.log[0], "w") as log:  # noqa: F821
    configure_logging(log)
    point = study.point(w.point)
    spec = RunSpec(study.model, study.level, point.symmetry, snakemake.input.mesh)  # noqa: F821
    try:
        solve(point.config, spec, study.rung, snakemake.output[0],  # noqa: F821
              snakemake.params.checkpoint, snakemake.input.get("wall"))  # noqa: F821
    except MeshMotionRefused as err:
        # one line naming the point, in the log and in Snakemake's error report
        line = f"design point {w.design_study}/{point.id} refused before the solve: {err}"
        log.write(line + "\n")
        raise MeshMotionRefused(line) from None
