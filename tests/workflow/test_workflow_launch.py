"""ureterfsi.workflow.launch: the one command line of every solve rule (solve, ladder_run, design_solve,
design_escalated_solve, design_corner_solve), each rule's command built through it and read back by the study's
own parser; and a scan that refuses a rule file or workflow script that builds or runs a solve itself."""
import json
import re
import shlex
from pathlib import Path

import pytest

from ureterfsi.config import load_config_files, run_config
from ureterfsi.config.sections import rung_view
from ureterfsi.designs import jobs as design_jobs
from ureterfsi.designs.expand import studies
from ureterfsi.designs.rung_check import reference_config
from ureterfsi.study.cli import parser
from ureterfsi.workflow import launch, paths

REPO = Path(__file__).resolve().parents[2]
SOLVING_RULES = ("solve", "ladder_run", "design_solve", "design_escalated_solve", "design_corner_solve")
MPI = {"tasks": 4, "mpi": "mpiexec", "mumps_out_of_core": 1}


@pytest.fixture(scope="module")
def design():
    cfg = load_config_files([REPO / "config/config.yaml", REPO / "config/designs/hole_diameter_spacing.yaml"])
    return studies(cfg)["hole_diameter_spacing"]


def parsed(command: str):
    """The interpreter part and the parsed `-m ureterfsi.study` arguments of a solve command."""
    words = shlex.split(command)
    at = words.index("-m")
    assert words[at + 1] == launch.STUDY
    return words[:at], parser().parse_args(words[at + 2:])


def test_study_solve_command():
    job = launch.SolveJob("fully_coupled", "quarter", "3", "coarse", paths.mesh("quarter", "3", "coarse"),
                          paths.run("fully_coupled", "quarter", "3", "coarse"), paths.checkpoint("x"),
                          run_config=paths.run_config("fully_coupled", "3"), end=0.3)
    cmd = launch.command(job, MPI, python="py")
    assert cmd == ("mpiexec -n 4 py -m ureterfsi.study --run-config results/configs/fully_coupled/model3.json --model 3"
                   " --level coarse --symmetry quarter --fidelity fully_coupled"
                   " --mesh results/meshes/quarter/model3_coarse.msh"
                   " --out results/runs/fully_coupled/quarter/model3_coarse.nc --checkpoint results/checkpoints/x.npz"
                   " --end 0.3 --out-of-core 1")
    run, args = parsed(cmd)
    assert run == ["mpiexec", "-n", "4", "py"] and args.end == 0.3 and args.out_of_core == 1
    # a serial job: no MPI launcher however many tasks, in core unless the resource says otherwise
    serial = launch.command(launch.SolveJob("one_way", "quarter", "3", "coarse", "m", "o", "c", wall="w"),
                            {"tasks": 4}, python="py")
    assert serial.startswith("py -m ureterfsi.study ") and serial.endswith("--wall w --out-of-core 0")


def test_ladder_rung_command():
    rung = {"fidelity": "one_way", "symmetry": "quarter", "level": "coarse", "dt": 0.005}
    job = launch.SolveJob(rung["fidelity"], rung["symmetry"], "3", rung["level"], "m.msh", "r.nc", "c.npz",
                          run_config="c.json", end=0.1, dt=rung["dt"])
    _, args = parsed(launch.command(job, {}, python="py"))
    assert (args.fidelity, args.dt, args.end, args.run_config, args.checkpoint) == ("one_way", 0.005, 0.1, "c.json",
                                                                                    "c.npz")


def test_design_point_and_corner_commands(design):
    p = design.points[0]
    solve = design_jobs.point_solve(design, p.id)
    inputs = design_jobs.point_inputs(design, p.id)
    job = launch.SolveJob(**solve, mesh=inputs["mesh"], out=paths.design_run(design.name, p.id),
                          checkpoint=paths.checkpoint(f"designs/{design.name}/{p.id}"), wall=inputs.get("wall"))
    _, args = parsed(launch.command(job, MPI, python="py"))
    assert args.name == f"design point hole_diameter_spacing/{p.id}" and not args.record_failure
    assert args.wall == paths.design_wall_motion(p.wall_id) and args.fidelity == design.rung == "one_way"
    # the point's own configuration, whole through the shell quoting, as the solve reads it
    assert run_config(json.loads(args.run_sections), args.model)["geometry"] == p.config["geometry"]
    # the rerun trigger is the configuration the design rules always recorded
    assert json.loads(design_jobs.solve_trigger(solve))["rung"] == "one_way"
    c = design.check.corners[0]
    for rung in ("one_way", "fully_coupled"):
        solve = design_jobs.corner_solve(design, c.id, rung)
        inputs = design_jobs.corner_inputs(design, c.id, rung)
        job = launch.SolveJob(**solve, mesh=inputs["mesh"], out="o.nc", checkpoint="c.npz", wall=inputs.get("wall"))
        run, args = parsed(launch.command(job, MPI, python="py"))
        assert args.record_failure and args.name == f"rung-check corner hole_diameter_spacing/{c.id}"
        assert (args.wall is None) == (rung == "fully_coupled")
        assert run == (["mpiexec", "-n", "4", "py"] if rung == "fully_coupled" else ["py"])
        assert args.out_of_core == 1


def test_reference_and_escalated_commands():
    """A reference run on its own model and rung (stricture_holes: the unstented model 1 fully coupled r-z, the
    stented model 3 one-way) and an escalated point (fully coupled on the reference scheme), through the launcher."""
    cfg = load_config_files([REPO / "config/config.yaml", REPO / "config/designs/stricture_holes.yaml"])
    st = studies(cfg)["stricture_holes"]

    def command_of(solve, inputs, out):
        job = launch.SolveJob(**solve, mesh=inputs["mesh"], out=out, checkpoint="c.npz", wall=inputs.get("wall"))
        return parsed(launch.command(job, MPI, python="py"))

    for ref in st.references:
        run, args = command_of(design_jobs.point_solve(st, ref.id), design_jobs.point_inputs(st, ref.id),
                               paths.design_run(st.name, ref.id))
        assert (args.model, args.fidelity, args.symmetry) == (ref.model, ref.rung, ref.symmetry)
        assert (args.wall is None) == (ref.rung == "fully_coupled") and not args.record_failure
        assert run == ["py"]                              # r-z fully coupled and 3D one-way: serial
        assert run_config(json.loads(args.run_sections), args.model)["models"] == {ref.model: ref.config["models"][
            ref.model]}
    assert {r.model for r in st.references} == {"1", "3"}
    p = st.points[0]
    assert p.rung == "one_way"
    run, args = command_of(design_jobs.escalated_solve(st, p.id), design_jobs.escalated_inputs(st, p.id),
                           paths.escalated_run(st.name, p.id))
    assert (args.model, args.fidelity, args.wall, args.record_failure) == (st.model, "fully_coupled", None, False)
    assert args.name == f"design point stricture_holes/{p.id} (escalated)"
    assert run == ["mpiexec", "-n", "4", "py"] and args.out == paths.escalated_run(st.name, p.id)
    cfg_run = run_config(json.loads(args.run_sections), args.model)
    # the reference scheme's solver keys; the one-way keys (the point's one_way_mesh_motion: auto) at their defaults
    assert cfg_run["solver"] == rung_view(reference_config(p.config), "fully_coupled")["solver"]
    assert cfg_run["solver"]["one_way_mesh_motion"] != p.config["solver"]["one_way_mesh_motion"]
    assert cfg_run["ends"] == rung_view(p.config, "fully_coupled")["ends"]
    trigger = json.loads(design_jobs.solve_trigger(design_jobs.escalated_solve(st, p.id)))
    assert trigger["rung"] == "fully_coupled" != json.loads(design_jobs.solve_trigger(
        design_jobs.point_solve(st, p.id)))["rung"]


def rule_blocks(text: str) -> dict:
    """{rule name: its text} of a rule file (a block ends at the next rule or at a line indented less)."""
    blocks, name, indent = {}, None, 0
    for line in text.splitlines():
        m = re.match(r"^(\s*)rule (\w+):", line)
        if m:
            name, indent = m.group(2), len(m.group(1))
            blocks[name] = ""
            continue
        if name and line.strip() and len(line) - len(line.lstrip()) <= indent:
            name = None
        if name:
            blocks[name] += line + "\n"
    return blocks


# what only the launcher may spell: the solve module, its out-of-core option, an MPI launcher, an in-process solve
OWN_SOLVE = re.compile(r"ureterfsi\.study\b(?!\.\w)|--out-of-core|mpiexec|srun|\brun_solve\b|study\.run import")


def own_solves(files: dict) -> list[str]:
    """'file: rule or line' of every rule file / script that builds or runs a solve other than through the launcher:
    a solving rule whose shell is not launch.SHELL or whose command is not solve_command's, or any code line
    spelling what only the launcher spells."""
    found = []
    for path, text in files.items():
        # docstrings and comments say what runs where; code is what the scan reads (lines kept in place)
        code_text = re.sub(r'"""(.|\n)*?"""', lambda m: "\n" * m.group(0).count("\n"), text)
        for i, (line, code) in enumerate(zip(text.splitlines(), code_text.splitlines()), 1):
            if OWN_SOLVE.search(code.split("#", 1)[0]):
                found.append(f"{path}:{i}: {line.strip()}")
        if path.endswith(".smk"):
            for name, body in rule_blocks(text).items():
                if name in SOLVING_RULES and not (re.search(r"shell:\s*launch\.SHELL\b", body)
                                                  and "solve=solve_command(" in body):
                    found.append(f"{path}: rule {name} does not run launch.SHELL with solve_command")
    return found


def workflow_files() -> dict:
    files = {str(p.relative_to(REPO)): p.read_text() for p in sorted((REPO / "workflow/rules").glob("*.smk"))}
    files.update({str(p.relative_to(REPO)): p.read_text() for p in sorted((REPO / "workflow/scripts").glob("*.py"))})
    return files


def test_no_rule_or_script_builds_its_own_solve():
    files = workflow_files()
    blocks = {n for path, t in files.items() if path.endswith(".smk") for n in rule_blocks(t)}
    assert set(SOLVING_RULES) <= blocks, blocks
    assert own_solves(files) == []


def test_the_scan_finds_planted_own_solves():
    ok = 'rule solve:\n    params:\n        solve=solve_command(study_job),\n    shell:\n        launch.SHELL\n'
    assert own_solves({"a.smk": ok}) == []
    spelled = ok.replace("launch.SHELL", '"python -m ureterfsi.study --out-of-core 1 > {log}"')
    assert own_solves({"a.smk": spelled}) == ['a.smk:5: "python -m ureterfsi.study --out-of-core 1 > {log}"',
                                              "a.smk: rule solve does not run launch.SHELL with solve_command"]
    script = ('"""Runs ureterfsi.study (a mention)."""\n'
              'from ureterfsi.study.run import solve\nsolve(cfg, spec, "one_way", out)\n')
    assert own_solves({"s.py": script}) == ["s.py:2: from ureterfsi.study.run import solve"]
    nested = "if X:\n\n    rule design_solve:\n        script:\n            'x.py'\n"
    assert own_solves({"d.smk": nested}) == ["d.smk: rule design_solve does not run launch.SHELL with solve_command"]
