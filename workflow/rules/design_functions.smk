# Input functions, params and resources of the design stage (designs.smk), thin wrappers of
# ureterfsi.designs.jobs; included after common.smk.
from ureterfsi.designs import jobs as design_jobs
from ureterfsi.designs import question as hole_question


def design_figures(study):
    """The figure files of a design study (design_jobs.figures)."""
    return design_jobs.figures(DESIGNS[study], FIGURE_FORMATS)


def question_datasets():
    """The datasets of the studies that vary the hole-pair spacing on a grid (ureterfsi.designs.question.asks)."""
    return [
        paths.design_dataset(s) for s, st in DESIGNS.items() if hole_question.asks(st)
    ]


def design_field_figure_outputs(kind):
    """The field figure files of a design point (paths.design_field_figure), as design_figure_outputs."""
    return _design_outputs(paths.design_field_figure, kind)


def design_point_config(w):
    """The configuration of a design point (its run's: geometry, models, fluid)."""
    return DESIGNS[w.design_study].point(w.point).config


def design_point_values(w):
    """A design point's parameter values (SI units)."""
    return DESIGNS[w.design_study].point(w.point).values


def design_figure_outputs(kind):
    """The figure files of a design study's <kind> (paths.design_figure), one per configured format; the report format
    goes into the report (caption workflow/report/design_<kind>.rst)."""
    return _design_outputs(paths.design_figure, kind)


def _design_outputs(path_of, kind):
    out = []
    for ext in FIGURE_FORMATS:
        path = path_of(kind=kind, ext=ext)
        if ext == REPORT_FORMAT:
            caption = f"../report/design_{kind}.rst"
            path = report(path, caption=caption, category="Design studies")
        out.append(path)
    return out


def design_mesh_inputs(w):
    """Rerun trigger of a design mesh (design_jobs.mesh_trigger)."""
    return design_jobs.mesh_trigger(*DESIGN_MESHES[w.mesh_id])


def design_solve_inputs(w):
    """A design point's mesh and wall motion (design_jobs.point_inputs)."""
    return design_jobs.point_inputs(DESIGNS[w.design_study], w.point)


def design_escalated_inputs(w):
    """An escalated point's mesh (design_jobs.escalated_inputs)."""
    return design_jobs.escalated_inputs(DESIGNS[w.design_study], w.point)


def design_corner_inputs(w):
    """A corner's mesh and wall motion (design_jobs.corner_inputs)."""
    return design_jobs.corner_inputs(DESIGNS[w.design_study], w.corner, w.corner_rung)


def design_corner_runs(w):
    """The run files of a checked study's corners (design_jobs.corner_runs)."""
    return design_jobs.corner_runs(DESIGNS[w.design_study])


def design_dataset_inputs(w):
    """A study's point and reference runs and rung check (design_jobs.dataset_inputs); for a study that escalates,
    once checkpoint design_rung_check is made, the escalated points' fully coupled runs.
    """
    st = DESIGNS[w.design_study]
    made = None
    if design_jobs.escalates(st):
        made = checkpoints.design_rung_check.get(design_study=st.name).output[0]
    return design_jobs.dataset_inputs(st, made)


def design_rung_check_caption(wildcards, input):
    """The dataset's rung_check attribute for the captions (design_jobs.rung_check_caption); a function of input:
    Snakemake keeps it out of the rerun triggers, and evaluates it again when it writes the report.
    """
    return design_jobs.rung_check_caption(input[0])


def point_solve(w):
    """What a design point's solve is given (design_jobs.point_solve)."""
    return design_jobs.point_solve(DESIGNS[w.design_study], w.point)


def escalated_solve(w):
    """What an escalated design point's solve is given (design_jobs.escalated_solve)."""
    return design_jobs.escalated_solve(DESIGNS[w.design_study], w.point)


def corner_solve(w):
    """What a rung-check corner's solve is given (design_jobs.corner_solve)."""
    return design_jobs.corner_solve(DESIGNS[w.design_study], w.corner, w.corner_rung)


def point_rung(w):
    """(fidelity, symmetry, level) of a design point's solve."""
    return design_jobs.rung(point_solve(w))


def escalated_rung(w):
    """(fidelity, symmetry, level) of an escalated design point's solve."""
    return design_jobs.rung(escalated_solve(w))


def corner_rung(w):
    """(fidelity, symmetry, level) of a rung-check corner's solve."""
    return design_jobs.rung(corner_solve(w))


def point_scheme(w):
    """solver.fully_coupled_scheme of a design point's solve (its memory reservation)."""
    return design_jobs.scheme(point_solve(w))


def escalated_scheme(w):
    """solver.fully_coupled_scheme of an escalated design point's solve."""
    return design_jobs.scheme(escalated_solve(w))


def corner_scheme(w):
    """solver.fully_coupled_scheme of a rung-check corner's solve."""
    return design_jobs.scheme(corner_solve(w))


def design_job(solve, name, input, output):
    """The solve (launch.SolveJob) given solve, its checkpoint named name."""
    files = {"mesh": input.mesh, "out": output[0], "wall": input.get("wall")}
    return launch.SolveJob(**solve, **files, checkpoint=paths.checkpoint(name))


def point_job(w, input, output):
    """A design point's solve."""
    name = f"designs/{w.design_study}/{w.point}"
    return design_job(point_solve(w), name, input, output)


def escalated_job(w, input, output):
    """An escalated design point's solve."""
    name = f"designs/{w.design_study}/{w.point}_fully_coupled"
    return design_job(escalated_solve(w), name, input, output)


def corner_job(w, input, output):
    """A rung-check corner's solve."""
    name = f"designs/{w.design_study}/rung_check/{w.corner}_{w.corner_rung}"
    return design_job(corner_solve(w), name, input, output)
