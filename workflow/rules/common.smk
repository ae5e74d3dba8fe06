# Shared part of the workflow rules: the configuration validated, lists derived from it, the local memory
# budget, wildcard constraints, and what every stage needs: the study's run files, figure outputs and the
# resources and command of a solve (the decisions: ureterfsi.workflow.resources and .launch, the paths:
# ureterfsi.workflow.paths). The stages' own input functions: solve_functions.smk, design_functions.smk (their
# logic in the package).
import json
import sys

from snakemake.exceptions import WorkflowError

from ureterfsi.designs import expand as ureter_designs
from ureterfsi.config import (
    ConfigError,
    deep_merge,
    read_config_args,
    read_yaml,
    unmakeable,
    run_sections,
    validate_config,
    wall_sections,
)
from ureterfsi.workflow import launch, paths
from ureterfsi.workflow import resources as decide
from ureterfsi.workflow.machine import physical_memory_mib
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


def solve_priority(w):
    """Scheduling priority of a study solve and of its mesh (decide.solve_priority: finer levels first, then the
    models with more side holes)."""
    return decide.solve_priority(config, w.model, w.level)


def solve_mem_mb(fidelity, symmetry, level, scheme=None):
    """MiB a solve reserves (resource mem_mb; ureterfsi.workflow.resources.solve_mem_mb)."""
    return decide.solve_mem_mb(config, fidelity, symmetry, level, scheme)


def memory_budget():
    """MiB one job may hold: what the site says a node has (config cluster, the same in a cluster job as on the
    submit host), else on a cluster None (unknown), else the local budget."""
    node = config["cluster"]["mem_mb_per_node"]
    if node is not None or CLUSTER_RUN:
        return node
    budget = workflow.global_resources.get("mem_mb")
    return getattr(budget, "raw", budget)


# The resources and command of a solve rule, from rung(w): the (fidelity, symmetry, level) of its solve, and
# scheme(w): its solver.fully_coupled_scheme where it is not the configuration's (a design study's), else None.


def out_of_core(rung, scheme=lambda w: None):
    """Resource mumps_out_of_core: decide.out_of_core against memory_budget (a local run caps its reservation at
    the budget, a cluster run at the node's memory). A resource, not a param: it does not change the solution,
    so a changed budget must not re-run a finished solve (params are a rerun trigger).
    """
    return lambda w: decide.out_of_core(config, *rung(w), memory_budget(), scheme(w))


def solve_mpi(rung):
    """Resource mpi (decide.mpi_resource: the local launcher of an MPI-capable solve, none for a serial one)."""
    return lambda w: decide.mpi_resource(*rung(w)[:2])


def solve_mem_mb_of(rung, run, scheme=lambda w: None):
    """Resource mem_mb (solve_mem_mb). On a cluster, a solve that needs more than a node has
    (cluster.mem_mb_per_node) and cannot keep its factors on disk is refused before submission, naming run(w).
    """

    def mem_mb(w):
        why = decide.node_refusal(
            config, *rung(w), config["cluster"]["mem_mb_per_node"], scheme(w)
        )
        if why:
            raise WorkflowError(f"{run(w)} {why}")
        return solve_mem_mb(*rung(w), scheme(w))

    return mem_mb


def solve_command(job):
    """Params `solve` of every solve (its shell is launch.SHELL): launch.command of job(w, input, output), a
    launch.SolveJob. A function of resources: Snakemake keeps it out of the rerun triggers.
    """
    return lambda w, input, output, resources: launch.command(
        job(w, input, output), resources
    )
