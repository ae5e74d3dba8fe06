"""What the design rules (workflow/rules/designs.smk) ask of the expanded studies, as plain functions: the shared
meshes and wall motions by id, each job's inputs and configuration (its rerun trigger), the rung a solve runs on
(its memory reservation and out-of-core factorisation), what its solve command is given
(ureterfsi.workflow.launch.SolveJob: a point or reference run on its own model and rung, a corner on the study's
rung or fully coupled, an escalated point fully coupled), the dataset's runs (escalated ones once the rung check
is made) and a study's figures."""
from __future__ import annotations

import json

from ureterfsi.config.runs import run_config
from ureterfsi.config.sections import mesh_sections, run_sections
from ureterfsi.data.provenance import config_hash
from ureterfsi.designs import expand
from ureterfsi.designs.passage import escalated_from_file
from ureterfsi.designs.rung_check import REFERENCE_RUNG, reference_config
from ureterfsi.designs.space import Point, Study
from ureterfsi.workflow import paths


def meshes(designs: dict) -> dict:
    """{mesh id: (study, point)} of every point, reference and corner of the studies (a mesh shared by several: one
    of them)."""
    return {p.mesh_id: (st, p) for st in designs.values() for p in expand.points_and_corners(st)}


def walls(designs: dict) -> dict:
    """{wall id: point} of every point, reference and corner on the one-way rung (their shared r-z wall motions)."""
    return {p.wall_id: p for st in designs.values() for p in expand.points_and_corners(st) if p.wall_id}


def mesh_trigger(st: Study, p: Point) -> str:
    """The configuration entering a design mesh (rule design_mesh's rerun trigger), on the model it solves."""
    return json.dumps(mesh_sections(p.config, p.model, st.level, p.symmetry), sort_keys=True)


def point_inputs(st: Study, point_id: str) -> dict:
    """A point's (or reference run's) mesh, and on the one-way rung its wall motion."""
    p = st.point(point_id)
    out = {"mesh": paths.design_mesh(p.mesh_id)}
    if p.wall_id:
        out["wall"] = paths.design_wall_motion(p.wall_id)
    return out


def corner_inputs(st: Study, corner_id: str, rung: str) -> dict:
    """A corner's mesh, and on the one-way rung its wall motion (the fully coupled solve moves its own wall)."""
    c = st.check.corner(corner_id)
    out = {"mesh": paths.design_mesh(c.mesh_id)}
    if rung == "one_way":
        out["wall"] = paths.design_wall_motion(c.wall_id)
    return out


def escalated_inputs(st: Study, point_id: str) -> dict:
    """An escalated point's mesh (its fully coupled solve moves its own wall)."""
    return {"mesh": paths.design_mesh(st.point(point_id).mesh_id)}


def _solve(st: Study, p: Point, cfg: dict, rung: str, name: str, record_failure: bool) -> dict:
    return {"fidelity": rung, "symmetry": p.symmetry, "model": p.model, "level": st.level,
            "sections": json.dumps(run_sections(cfg, p.model, rung), sort_keys=True), "name": name,
            "record_failure": record_failure}


def point_solve(st: Study, point_id: str) -> dict:
    """What a point's (or reference run's) solve command is given (the fields of ureterfsi.workflow.launch.SolveJob
    but its files): its model, rung, symmetry and configuration, the study's level; a failure fails the job, naming
    the point."""
    p = st.point(point_id)
    return _solve(st, p, p.config, p.rung, f"design point {st.name}/{p.id}", False)


def escalated_solve(st: Study, point_id: str) -> dict:
    """The same of a point escalated by the rung check (rung_check.on_failure: escalate): fully coupled
    (rung_check.REFERENCE_RUNG) on its configuration with the reference scheme (rung_check.reference_config)."""
    p = st.point(point_id)
    name = f"design point {st.name}/{p.id} (escalated)"
    return _solve(st, p, reference_config(p.config), REFERENCE_RUNG, name, False)


def solve_config_hash(st: Study, point_id: str, rung: str) -> str:
    """The config_hash (data.provenance) the run file of a point's (or reference's) solve on `rung` records: that of
    the configuration its solve is given (point_solve; escalated_solve for the fully coupled run of a point off that
    rung), as the solve reads it (config.run_config)."""
    return _config_hash(point_solve(st, point_id) if rung == st.point(point_id).rung else escalated_solve(st, point_id))


def corner_config_hash(st: Study, corner_id: str, rung: str) -> str:
    """The same of a rung-check corner's solve on `rung` (corner_solve; a corner that reuses a point's run on the
    study's rung has that point's configuration there)."""
    return _config_hash(corner_solve(st, corner_id, rung))


def _config_hash(solve: dict) -> str:
    return config_hash(run_config(json.loads(solve["sections"]), solve["model"]))


def corner_solve(st: Study, corner_id: str, rung: str) -> dict:
    """The same of a corner's solve on `rung` (the study's or the fully coupled reference): a failure is recorded
    in its run file (the rung is not checked there, which the study's rung check reports) and the job succeeds,
    so that the study's other corners and its points are still made."""
    c, cfg = expand.corner_solve_request(st, corner_id, rung)
    return _solve(st, c, cfg, rung, f"rung-check corner {st.name}/{c.id}", True)


def solve_trigger(solve: dict) -> str:
    """The configuration entering a point's, reference's, escalated point's or corner's solve, with its rung and
    symmetry (rerun trigger)."""
    sections = json.loads(solve["sections"])
    return json.dumps(sections | {"rung": solve["fidelity"], "symmetry": solve["symmetry"]}, sort_keys=True)


def rung(solve: dict) -> tuple[str, str, str]:
    """(fidelity, symmetry, level) of a point's or corner's solve: its memory reservation is a study solve's there."""
    return solve["fidelity"], solve["symmetry"], solve["level"]


def scheme(solve: dict) -> str:
    """The solve's solver.fully_coupled_scheme (its memory reservation's entry, workflow.resources.memory_entry)."""
    return json.loads(solve["sections"])["solver"]["fully_coupled_scheme"]


def escalates(st: Study) -> bool:
    """Whether the study's dataset waits for its rung check to know its runs (rung_check.on_failure: escalate)."""
    return bool(st.check) and st.check.on_failure == "escalate"


def runs(st: Study) -> list[str]:
    """The run files of the study's points and reference runs on their own rungs."""
    return [paths.design_run(st.name, p.id) for p in st.points + st.references]


def dataset_inputs(st: Study, check_file=None) -> dict:
    """The study's point and reference runs, and for a checked study its rung check (checkpoint design_rung_check);
    given the made check's file (a study that escalates), the escalated points' fully coupled runs in place of
    theirs (passage.escalated_from_file)."""
    escalated = escalated_from_file(st, check_file) if check_file is not None else []
    out = {"runs": [paths.escalated_run(st.name, p.id) if p.id in escalated else paths.design_run(st.name, p.id)
                    for p in st.points + st.references]}
    if st.check:
        out["check"] = paths.rung_check(st.name)
    return out


def corner_runs(st: Study) -> list[str]:
    """The run files of a checked study's corners (rung, fully coupled; expand.corner_run_paths)."""
    return [f for pair in expand.corner_run_paths(st).values() for f in pair]


# the field figures of a point design_studies.<study>.field_figures selects (ureterfsi.plotting.fields)
FIELD_FIGURE_KINDS = ("field_hole_flow", "field_stent_wss")


def figures(st: Study, formats) -> list[str]:
    """The figure files of a design study (expand.design_figure_kinds, and FIELD_FIGURE_KINDS of its field_points),
    one per format."""
    return ([paths.design_figure(st.name, k, ext) for k in expand.design_figure_kinds(st) for ext in formats]
            + [paths.design_field_figure(st.name, p, k, ext) for p in st.field_points for k in FIELD_FIGURE_KINDS
               for ext in formats])


def rung_check_caption(dataset_path) -> str:
    """A design dataset's rung_check attribute for the figure captions; what it will be before the dataset exists
    (or is the empty file of `snakemake --touch`)."""
    import xarray as xr

    try:
        with xr.open_dataset(dataset_path, decode_times=False) as ds:
            return str(ds.attrs.get("rung_check", "not recorded in the dataset"))
    except (OSError, ValueError):
        return "measured when the study's dataset is made (its attribute rung_check)"
