"""Snakemake script of rule `design_solve`: one design point on its study's rung (ureterfsi.study.cli.solve).
A point that cannot be solved (refused before the solve, a step that fails, an inverted mesh) ends in one line
naming the point, in the rule's log and in Snakemake's error report (ureterfsi.workflow_log.run_script)."""
import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

from ureterfsi.designs import studies  # noqa: E402
from ureterfsi.fsi import SolveFailure  # noqa: E402
from ureterfsi.study.cli import solve  # noqa: E402
from ureterfsi.study.oneway import MeshMotionRefused  # noqa: E402
from ureterfsi.study.options import RunSpec  # noqa: E402
from ureterfsi.workflow_log import run_script  # noqa: E402


def main(smk):
    w = smk.wildcards
    study = studies(smk.config)[w.design_study]
    point = study.point(w.point)
    spec = RunSpec(study.model, study.level, point.symmetry, smk.input.mesh)
    try:
        solve(point.config, spec, study.rung, smk.output[0], smk.params.checkpoint, smk.input.get("wall"))
    except MeshMotionRefused as err:
        raise MeshMotionRefused(f"design point {w.design_study}/{point.id} refused before the solve: {err}") from None
    except SolveFailure as err:
        raise SolveFailure(f"design point {w.design_study}/{point.id} ({study.rung}) failed: {err}") from None


run_script(snakemake, lambda: main(snakemake))  # noqa: F821
