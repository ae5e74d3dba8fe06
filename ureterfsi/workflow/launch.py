"""The one command line of every solve job of the workflow (rules solve, ladder_run, design_solve,
design_escalated_solve, design_corner_solve): `python -m ureterfsi.study` with the run's arguments, behind the MPI
launcher for several tasks (resources.launcher), with the job's out-of-core factorisation and checkpoint, its
output into the rule's log. The rules describe their solve (SolveJob) and take the command from here, so that no
option of one rule's solve drifts from another's (tests/workflow/test_workflow_launch.py builds every rule's command and
refuses a rule that spells its own)."""
from __future__ import annotations

import shlex
import sys
from dataclasses import dataclass

from .resources import launcher

STUDY = "ureterfsi.study"   # the module every solve job runs (ureterfsi.study.cli)


@dataclass(frozen=True)
class SolveJob:
    """What one solve job runs: its rung, model, mesh symmetry and level, files, and the options it sets.
    `run_config` is the file of the solve's configuration sections (rule solve_config), `sections` the same inline
    (JSON text: a design point's, reference run's, escalated point's or corner's own configuration on its model);
    `name` the run a failure names; `record_failure`: a failed solve writes a run file holding its failure instead
    of failing the job (a rung-check corner)."""
    fidelity: str
    symmetry: str
    model: str
    level: str
    mesh: str
    out: str
    checkpoint: str
    run_config: str | None = None
    sections: str | None = None
    wall: str | None = None
    end: float | None = None
    dt: float | None = None
    name: str | None = None
    record_failure: bool = False


def arguments(job: SolveJob, out_of_core: int = 0) -> list[str]:
    """The arguments of `python -m ureterfsi.study` for `job` (out_of_core: resource mumps_out_of_core)."""
    args = []
    if job.run_config is not None:
        args += ["--run-config", job.run_config]
    if job.sections is not None:
        args += ["--run-sections", job.sections]
    args += ["--model", job.model, "--level", job.level, "--symmetry", job.symmetry, "--fidelity", job.fidelity,
             "--mesh", job.mesh, "--out", job.out, "--checkpoint", job.checkpoint]
    for flag, value in (("--end", job.end), ("--dt", job.dt), ("--wall", job.wall), ("--name", job.name)):
        if value is not None:
            args += [flag, str(value)]
    if job.record_failure:
        args.append("--record-failure")
    return args + ["--out-of-core", str(int(out_of_core))]


def command(job: SolveJob, resources, python: str = sys.executable) -> str:
    """The shell command of a solve job: its interpreter (behind `<mpi> -n <tasks>` for an MPI-capable solve given
    several tasks), `-m ureterfsi.study` and its arguments, every one quoted for the shell. `resources`: the
    job's (tasks, mpi, mumps_out_of_core; absent: 1 task, serial, in core). The rule sends the output to its log
    (LOG)."""
    run = launcher(job.fidelity, job.symmetry, resources.get("tasks", 1), resources.get("mpi"), python)
    args = arguments(job, resources.get("mumps_out_of_core", 0))
    return f"{run} -m {STUDY} " + " ".join(shlex.quote(a) for a in args)


# the shell directive of every solve rule: the command (params.solve, command), its output into the rule's log;
# a failed solve's last line (its one-line error) also to stderr, where Snakemake's error report shows it
SHELL = "{params.solve} > {log} 2>&1 || (tail -n 1 {log} >&2; exit 1)"
