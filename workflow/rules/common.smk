# Shared part of the workflow rules: lists derived from the config, the local memory budget, wildcard
# constraints, and every function the rule files call (input functions, params, resources; the resource decisions
# themselves: ureterfsi.workflow.resources, the paths: ureterfsi.workflow.paths).
import json
import sys

from snakemake.exceptions import WorkflowError
from snakemake.resources import Resource

from ureterfsi.designs import expand as ureter_designs
from ureterfsi.designs.passage import escalated_from_file
from ureterfsi.designs.rung_check import REFERENCE_RUNG, reference_config
from ureterfsi.config import (
    ConfigError,
    deep_merge,
    mesh_sections,
    read_config_args,
    one_way_unposable,
    read_yaml,
    run_sections,
    unmakeable,
    validate_config,
    wall_sections,
)
from ureterfsi.workflow import paths
from ureterfsi.workflow import resources as decide
from ureterfsi.workflow.machine import physical_memory_mib
from ureterfsi.stability import case_by_name, case_setup
from ureterfsi.stability import cases as stability_cases

# Validation at the edge: one clear line naming the key and the constraint, non-zero exit, no output.
# Every config file is re-read by read_yaml (Snakemake's loader lets a key given twice win silently), and the
# --config values by read_config_args (Snakemake's parser makes every nested scalar a string).
try:
    for path in workflow.configfiles:
        read_yaml(path)
    config.update(
        deep_merge(config, read_config_args(workflow.config_settings.config_args))
    )
    validate_config(config)
except ConfigError as err:
    sys.stderr.write(f"{err}\n")
    sys.exit(2)


MODELS = sorted(config["models"])
LEVELS = list(config["mesh"]["levels"])
SYMMETRY = config["mesh"]["symmetry"]
FIDELITY = config["study"]["fidelity"]
STUDY_LEVEL = config["study"]["level"]
CONVERGENCE_MODEL = str(config["study"]["convergence_model"])
FIGURE_OPTIONS = config["figures"]
FIGURE_FORMATS = list(FIGURE_OPTIONS["formats"])
# the report shows one file per figure: the raster format when there is one
REPORT_FORMAT = "png" if "png" in FIGURE_FORMATS else FIGURE_FORMATS[0]
DESIGNS = ureter_designs.studies(config)
STABILITY_CASES = (
    [c.name for c in stability_cases(config)] if "stability" in config else []
)

# Memory budget of local runs. Solves reserve mem_mb (study.memory_mb), but Snakemake holds reservations only
# against a global `--resources mem_mb=...`, which the command line or a profile sets - and the workflow profile
# under workflow/profiles/ is not searched when the Snakefile sits at the repository root. Without a budget a
# plain `snakemake --cores 2` started the fine and medium runs side by side, more than the machine holds
# (docs/performance.md, Memory). So unless one is given, a local run budgets the machine's memory less
# study.memory_headroom_mb. A cluster run
# (--jobs: resource_settings.nodes; the executor itself is not known yet when the Snakefile is read) gets none:
# its scheduler holds each job's mem_mb, and a budget of the submit host's memory would cap every job's.
CLUSTER_RUN = workflow.resource_settings.nodes is not None
if not CLUSTER_RUN and "mem_mb" not in workflow.global_resources:
    workflow.register_resource(
        "mem_mb", decide.local_memory_budget(config, physical_memory_mib())
    )


# model and level as the schema spells them (not only the configured ones): refuse_unmakeable
# names the reason
wildcard_constraints:
    model="[1-9][0-9]*",
    level="[A-Za-z][A-Za-z0-9_]*",
    symmetry="full|half|quarter|axisymmetric",
    fidelity="fully_coupled|one_way",


def run_symmetry(model):
    """Mesh symmetry of a model's study runs: mesh.symmetry unless study.runs overrides it."""
    return config["study"]["runs"].get(str(model), {}).get("symmetry", SYMMETRY)


def run_fidelity(model):
    """Fidelity rung of a model's study runs: study.fidelity unless study.runs overrides it."""
    return config["study"]["runs"].get(str(model), {}).get("fidelity", FIDELITY)


def run_file(model, level):
    """Per-run probe dataset of one stent model on one mesh level (written by the solve rule), at the
    model's fidelity rung and mesh symmetry (study.fidelity, mesh.symmetry, study.runs).
    """
    return paths.run(run_fidelity(model), run_symmetry(model), model, level)


def mesh_sidecar(model, level):
    """JSON sidecar of the mesh of one stent model on one mesh level (the mesh its study runs use)."""
    return paths.mesh(run_symmetry(model), model, level, "json")


def figure_outputs(stem, category="Paper figures"):
    """The figure files of <stem> (paths.figure), one per configured format; the report format goes into the report
    (caption workflow/report/<stem>.rst)."""
    out = []
    for ext in FIGURE_FORMATS:
        path = paths.figure(stem, ext)
        if ext == REPORT_FORMAT:
            path = report(path, caption=f"../report/{stem}.rst", category=category)
        out.append(path)
    return out


def level_priority(w):
    """Scheduling priority of a level's mesh and solve jobs (decide.level_priority: finer levels first)."""
    return decide.level_priority(config, w.level)


def solve_mem_mb(fidelity, symmetry, level):
    """MiB a solve reserves (resource mem_mb; ureterfsi.workflow.resources.solve_mem_mb)."""
    return decide.solve_mem_mb(config, fidelity, symmetry, level)


def memory_budget():
    """MiB one job may hold: what the site says a node has (config cluster, the same in a cluster job as on the
    submit host), else on a cluster None (unknown), else the local budget."""
    node = config["cluster"]["mem_mb_per_node"]
    if node is not None or CLUSTER_RUN:
        return node
    budget = workflow.global_resources.get("mem_mb")
    return getattr(budget, "raw", budget)


def study_rung(w):
    """(fidelity, symmetry, level) of a study solve: its wildcards."""
    return w.fidelity, w.symmetry, w.level


def ladder_rung(w):
    """(fidelity, symmetry, level) of a ladder rung (config ladder.rungs)."""
    rung = config["ladder"]["rungs"][w.rung]
    return rung["fidelity"], rung["symmetry"], rung["level"]


def out_of_core(rung):
    """Resource mumps_out_of_core of a solve whose (fidelity, symmetry, level) is rung(w): decide.out_of_core
    against memory_budget (a local run caps its reservation at the budget, a cluster run at the node's memory).
    A resource, not a param: it does not change the solution, so a changed budget must not re-run a finished
    solve (params are a rerun trigger)."""
    return lambda w: decide.out_of_core(config, *rung(w), memory_budget())


def refuse_unmakeable(w):
    """Input function (no input) of the mesh rule; a mesh the configuration cannot make, and so every run
    on it, is refused before any job starts, in one line on stderr (an exception here would print a
    traceback)."""
    reason = unmakeable(config, w.model, w.level, w.symmetry)
    if reason:
        sys.stderr.write(
            f"target error: {paths.mesh(w.symmetry, w.model, w.level)}: {reason}\n"
        )
        sys.exit(2)
    return []


def run_config_file(model):
    """The configuration file of a model's solves: config.run_sections as JSON, written by rule solve_config."""
    return paths.run_config(model)


def solve_mpi(rung):
    """Resource mpi of a solve whose (fidelity, symmetry, level) is rung(w) (decide.mpi_resource)."""
    return lambda w: decide.mpi_resource(*rung(w)[:2])


def solve_job_mem_mb(w):
    """Resource mem_mb of a solve (solve_mem_mb). On a cluster, a solve that needs more than a node has
    (cluster.mem_mb_per_node) and cannot keep its factors on disk (out_of_core) is refused before submission.
    """
    why = decide.node_refusal(
        config, w.fidelity, w.symmetry, w.level, config["cluster"]["mem_mb_per_node"]
    )
    if why:
        raise WorkflowError(
            f"{paths.run(w.fidelity, w.symmetry, w.model, w.level)} {why}"
        )
    return solve_mem_mb(w.fidelity, w.symmetry, w.level)


def solve_launcher(rung):
    """Params function: the interpreter of `-m ureterfsi.study`, behind the MPI launcher for several tasks
    (decide.launcher; a function of resources: Snakemake keeps it out of the rerun triggers).
    """
    return lambda w, resources: decide.launcher(
        *rung(w)[:2], resources.get("tasks", 1), resources.get("mpi"), sys.executable
    )


def solve_inputs(w):
    """The mesh and the configuration file, and for the one-way rung the shared wall motion."""
    inputs = {
        "mesh": paths.mesh(w.symmetry, w.model, w.level),
        "config": run_config_file(w.model),
    }
    if w.fidelity == "one_way":
        if one_way_unposable(config):  # refused before any job starts, in one line
            sys.stderr.write(
                f"target error: {paths.run('one_way', w.symmetry, w.model, w.level)}: "
                f"{one_way_unposable(config)}\n"
            )
            sys.exit(2)
        inputs["wall"] = paths.WALL_MOTION
    return inputs


def solve_wall(wildcards, input):
    """--wall of a one-way solve (the shared wall motion); nothing for the fully coupled rung."""
    return f"--wall {input.wall}" if "wall" in input.keys() else ""


def convergence_only_end(w):
    """Runs that only the mesh-convergence study needs (its model on a level other than study.level) stop at
    study.convergence_time: Fig. 3 and the GCI look no further (the scene models only what it needs).
    """
    if w.level != STUDY_LEVEL and w.model == CONVERGENCE_MODEL:
        return f"--end {config['study']['convergence_time']}"
    return ""


def stability_mesh(w):
    """The r-z mesh of the case's level (case_setup names a level missing from mesh.levels); none for a
    hole_elements case, whose mesh sizes are its own (built in the case)."""
    s = case_setup(config, case_by_name(config, w.case))
    if s["scene"] == "holes":
        return []
    return paths.mesh("axisymmetric", s["model"], s["level"])


def stability_memory(w):
    """MiB a case reserves: that of a study solve of its scene (solve_mem_mb): r-z fully coupled, or 3D one-way
    at the case's level and symmetry."""
    s = case_setup(config, case_by_name(config, w.case))
    if s["scene"] == "holes":
        return solve_mem_mb("one_way", s["symmetry"], s["level"])
    return solve_mem_mb("fully_coupled", "axisymmetric", s["level"])


def stability_inputs(w):
    """The configuration entering one case (a change re-runs that case; plotting options do not)."""
    case = case_by_name(config, w.case)
    keys = ("geometry", "fluid", "ureter", "stent", "peristalsis", "time", "solver")
    st = {k: v for k, v in config["stability"].items() if k != "axes"}
    s = case_setup(config, case)
    mesh = {"mesh": s["cfg"]["mesh"]} if s["scene"] == "holes" else {}
    return json.dumps(
        {k: config[k] for k in keys}
        | mesh
        | {
            "stability": st,
            "axis": case.axis,
            "value": case.value,
            "model": config["models"][s["model"]],
        },
        sort_keys=True,
    )


def design_figures(study):
    """The figure files of a design study: parameters; a map for a full-factorial grid over two or more
    parameters with two or more values; sensitivity for sampled studies."""
    return [
        paths.design_figure(study, k, ext)
        for k in ureter_designs.design_figure_kinds(DESIGNS[study])
        for ext in FIGURE_FORMATS
    ]


def design_figure_outputs(kind):
    """The figure files of a design study's <kind> (paths.design_figure), one per configured format; the report format
    goes into the report (caption workflow/report/design_<kind>.rst)."""
    out = []
    for ext in FIGURE_FORMATS:
        path = paths.design_figure(kind=kind, ext=ext)
        if ext == REPORT_FORMAT:
            path = report(
                path, caption=f"../report/design_{kind}.rst", category="Design studies"
            )
        out.append(path)
    return out


def design_mesh_inputs(w):
    """The configuration entering a design mesh (rule design_mesh's rerun trigger)."""
    st, p = DESIGN_MESHES[w.mesh_id]
    return json.dumps(
        mesh_sections(p.config, p.model, st.level, p.symmetry),
        sort_keys=True,
    )


def design_solve_inputs(w):
    """The point's mesh, and on the one-way rung its wall motion."""
    p = DESIGNS[w.design_study].point(w.point)
    out = {"mesh": paths.design_mesh(p.mesh_id)}
    if p.wall_id:
        out["wall"] = paths.design_wall_motion(p.wall_id)
    return out


def design_solve_study(w):
    """The configuration entering a design point's (or reference run's) solve, with its rung and symmetry (rerun
    trigger)."""
    p = DESIGNS[w.design_study].point(w.point)
    sections = run_sections(p.config, p.model)
    return json.dumps(
        sections | {"rung": p.rung, "symmetry": p.symmetry}, sort_keys=True
    )


def design_solve_mem_mb(w):
    """MiB a design point's solve reserves: that of a study solve on its rung, symmetry and level."""
    st = DESIGNS[w.design_study]
    p = st.point(w.point)
    return solve_mem_mb(p.rung, p.symmetry, st.level)


def design_escalated_mesh(w):
    """An escalated point's mesh (its fully coupled solve moves its own wall)."""
    return paths.design_mesh(DESIGNS[w.design_study].point(w.point).mesh_id)


def design_escalated_study(w):
    """The configuration entering a design point's escalated (fully coupled) solve (rerun trigger)."""
    p = DESIGNS[w.design_study].point(w.point)
    sections = run_sections(reference_config(p.config), p.model)
    return json.dumps(
        sections | {"rung": REFERENCE_RUNG, "symmetry": p.symmetry}, sort_keys=True
    )


def design_escalated_mem_mb(w):
    """MiB a design point's escalated solve reserves: that of a fully coupled study solve."""
    st = DESIGNS[w.design_study]
    return solve_mem_mb(REFERENCE_RUNG, st.point(w.point).symmetry, st.level)


def design_corner_inputs(w):
    """A corner's mesh, and on the one-way rung its wall motion (the fully coupled solve moves its own wall)."""
    c = DESIGNS[w.design_study].check.corner(w.corner)
    out = {"mesh": paths.design_mesh(c.mesh_id)}
    if w.corner_rung == "one_way":
        out["wall"] = paths.design_wall_motion(c.wall_id)
    return out


def design_corner_study(w):
    """The configuration entering a corner's solve, with its rung and symmetry (rerun trigger)."""
    st = DESIGNS[w.design_study]
    c, cfg = ureter_designs.corner_solve_request(st, w.corner, w.corner_rung)
    sections = run_sections(cfg, st.model)
    return json.dumps(
        sections | {"rung": w.corner_rung, "symmetry": c.symmetry}, sort_keys=True
    )


def design_corner_mem_mb(w):
    """MiB a corner's solve reserves: that of a study solve on its rung, symmetry and level."""
    st = DESIGNS[w.design_study]
    return solve_mem_mb(w.corner_rung, st.check.corner(w.corner).symmetry, st.level)


def design_dataset_inputs(w):
    """The study's point and reference runs, and for a checked study its rung check (checkpoint design_rung_check);
    under rung_check.on_failure: escalate, once the check is made, the escalated points' fully coupled runs in place
    of theirs (ureterfsi.designs.passage.escalated_points)."""
    st = DESIGNS[w.design_study]
    escalated = []
    if st.check and st.check.on_failure == "escalate":
        made = checkpoints.design_rung_check.get(design_study=st.name).output[0]
        escalated = escalated_from_file(st, made)
    out = {
        "runs": [
            (
                paths.escalated_run(st.name, p.id)
                if p.id in escalated
                else paths.design_run(st.name, p.id)
            )
            for p in st.points + st.references
        ]
    }
    if st.check:
        out["check"] = paths.rung_check(st.name)
    return out


def design_corner_runs(w):
    """The run files of a checked study's corners (rung, fully coupled; ureterfsi.designs.expand.corner_run_paths)."""
    pairs = ureter_designs.corner_run_paths(DESIGNS[w.design_study]).values()
    return [f for pair in pairs for f in pair]


def design_rung_check_caption(wildcards, input):
    """The dataset's rung_check attribute for the figure captions, once the dataset exists (a function of input:
    Snakemake keeps it out of the rerun triggers, and evaluates it again when it writes the report).
    """
    import xarray as xr

    try:
        with xr.open_dataset(input[0], decode_times=False) as ds:
            return str(ds.attrs.get("rung_check", "not recorded in the dataset"))
    except (
        OSError,
        ValueError,
    ):  # not made yet (or an empty file of `snakemake --touch`)
        return "measured when the study's dataset is made (its attribute rung_check)"


def capped(resource, limit):
    """`resource` (a rule's value, callable or profile expression) evaluated, then at most `limit`."""

    def value(wildcards, input, attempt, threads, rulename, async_run):
        v = resource.evaluate(
            wildcards,
            input=input,
            attempt=attempt,
            threads=threads,
            rulename=rulename,
            async_run=async_run,
        ).value
        return min(v, limit) if isinstance(v, int) else v

    return Resource(resource.name, value)
