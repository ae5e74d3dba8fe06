"""Snakemake script of rules `design_solve` (one design point, or one of the study's reference runs, on its rung),
`design_escalated_solve` (a point fully coupled, where the rung check escalated it) and `design_corner_solve` (a
corner of the design space on the segment, on the study's rung or fully coupled: ureterfsi.designs.rung_check), through
ureterfsi.study.run.solve. A point that cannot be solved (refused before the solve, a step that fails, an inverted
mesh) ends in one line naming the point, in the rule's log and in Snakemake's error report
(ureterfsi.workflow.log.run_script). A corner's solve that fails is recorded instead (a run file holding the
failure, ureterfsi.designs.results.write_failed_corner): the rung is not checked there, which the study's rung check
reports; the job succeeds so that the study's other corners and its points are still made."""
import logging

from ureterfsi.designs.results import write_failed_corner
from ureterfsi.designs.expand import corner_solve_request, studies
from ureterfsi.designs.rung_check import REFERENCE_RUNG, reference_config
from ureterfsi.fsi import SolveFailure
from ureterfsi.study.run import solve
from ureterfsi.study.oneway import MeshMotionRefused
from ureterfsi.study.options import RunSpec
from ureterfsi.workflow.log import run_script


def main(smk):
    w = smk.wildcards
    study = studies(smk.config)[w.design_study]
    if smk.rule == "design_corner_solve":
        point, cfg = corner_solve_request(study, w.corner, w.corner_rung)
        rung, name = w.corner_rung, f"rung-check corner {w.design_study}/{point.id}"
    elif smk.rule == "design_escalated_solve":
        point = study.point(w.point)
        cfg, rung = reference_config(point.config), REFERENCE_RUNG
        name = f"design point {w.design_study}/{point.id} (escalated)"
    else:
        point = study.point(w.point)
        cfg, rung, name = point.config, point.rung, f"design point {w.design_study}/{point.id}"
    spec = RunSpec(point.model, study.level, point.symmetry, smk.input.mesh)
    try:
        solve(cfg, spec, rung, smk.output[0], smk.params.checkpoint, smk.input.get("wall"))
    except (MeshMotionRefused, SolveFailure) as err:
        what = "refused before the solve" if isinstance(err, MeshMotionRefused) else f"({rung}) failed"
        if smk.rule == "design_corner_solve":
            logging.getLogger("ureterfsi").error("%s %s, recorded as not checked: %s", name, what, err)
            write_failed_corner(cfg, smk.output[0], rung, f"{what}: {err}")
            return
        raise type(err)(f"{name} {what}: {err}") from None


run_script(snakemake, lambda: main(snakemake))  # noqa: F821
