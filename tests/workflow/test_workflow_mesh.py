"""Snakemake mesh rules (paper §2.4.1): dry run of the default target, one coarse mesh built by the workflow."""
import json
import subprocess
import sys
from pathlib import Path

import yaml

REPO = Path(__file__).resolve().parents[2]


def _snakemake(*args, cwd=REPO):
    return subprocess.run([sys.executable, "-m", "snakemake", *args], cwd=cwd, capture_output=True, text=True,
                          timeout=600)


def _jobs(stdout):
    """{output: {key: value}} of the jobs a dry run lists (the indented `key: value` lines of each job)."""
    jobs = {}
    for block in stdout.split("rule ")[1:]:
        fields = dict(line.strip().split(": ", 1) for line in block.splitlines()[1:]
                      if line.startswith("    ") and ": " in line)
        if "output" in fields:
            jobs[fields["output"].split(", ")[0]] = fields
    return jobs


def test_dry_run_of_default_target():
    """The default target plans every mesh and solve; the longest jobs (finest level) get the highest
    priority, and the default profile's memory budget fits the fine run beside the medium or a coarse one."""
    run = _snakemake("-n", "--forceall", "--cores", "2")
    assert run.returncode == 0, run.stderr[-3000:]
    assert "rule mesh:" in run.stdout
    jobs = _jobs(run.stdout)
    fine, medium, coarse = (jobs[f"results/runs/one_way/quarter/model3_{lv}.nc"] for lv in ("fine", "medium", "coarse"))
    assert int(fine["priority"]) > int(medium["priority"]) > int(coarse.get("priority", 0))
    assert int(jobs["results/meshes/quarter/model3_fine.msh"]["priority"]) == int(fine["priority"])
    # the r-z wall is solved once, first, for every one-way run (not by each run)
    wall = jobs["results/runs/one_way/wall_motion.nc"]
    assert int(wall["priority"]) > int(fine["priority"])
    for job in (fine, medium, coarse):
        assert "results/runs/one_way/wall_motion.nc" in job["input"]
    assert "wall_motion" not in jobs["results/runs/fully_coupled/axisymmetric/model1_coarse.nc"]["input"]
    mem = {k: int(dict(kv.split("=") for kv in job["resources"].split(", "))["mem_mb"])
           for k, job in (("fine", fine), ("medium", medium), ("coarse", coarse))}
    # reservations are for quarter meshes, scaled by the symmetry's factor (the ladder's half-model rung)
    ladder = _jobs(_snakemake("-n", "--forceall", "--cores", "2", "ladder").stdout)
    half = ladder["results/ladder/one_way_half.nc"]
    cfg = yaml.safe_load((REPO / "config/config.yaml").read_text())["study"]["memory_mb"]
    assert int(dict(kv.split("=") for kv in half["resources"].split(", "))["mem_mb"]) == \
        int(cfg["one_way"]["coarse"] * cfg["symmetry_factor"]["half"])
    profile = yaml.safe_load((REPO / "workflow/profiles/default/config.yaml").read_text())
    # the two mesh-study runs, the longest jobs, fit side by side (else the one whose mesh is ready first
    # starts and the other waits for it)
    assert mem["fine"] + mem["medium"] <= profile["resources"]["mem_mb"]
    assert mem["fine"] + mem["coarse"] <= profile["resources"]["mem_mb"]


def test_dry_run_of_stability_target():
    """The stability target plans one job per case: r-z cases on the workflow's r-z mesh, the 3D hole cases
    with no mesh input (each builds its own sizes) and the memory of a 3D one-way run."""
    run = _snakemake("-n", "--forceall", "--cores", "2", "stability")
    assert run.returncode == 0, run.stderr[-3000:]
    jobs = _jobs(run.stdout)
    cfg = yaml.safe_load((REPO / "config/config.yaml").read_text())["stability"]
    holes = [f"results/stability/hole_elements_{n:g}.nc" for n in cfg["axes"]["hole_elements"]]
    assert set(holes) <= set(jobs) and "results/stability/baseline.nc" in jobs
    assert jobs["results/stability/baseline.nc"]["input"] == "results/meshes/axisymmetric/model1_coarse.msh"

    def mem(job):
        return int(dict(kv.split("=") for kv in job["resources"].split(", "))["mem_mb"])

    for h in holes:
        assert "input" not in jobs[h] and mem(jobs[h]) > mem(jobs["results/stability/baseline.nc"])
    assert "results/figures/stability_map.png" in run.stdout


def test_workflow_builds_one_coarse_mesh(tmp_path):
    target = "results/meshes/quarter/model4_coarse"
    run = _snakemake("--snakefile", str(REPO / "Snakefile"), "--directory", str(tmp_path),
                     "--configfile", str(REPO / "config" / "config.yaml"), "--cores", "1", f"{target}.msh")
    assert run.returncode == 0, run.stderr[-3000:]
    assert (tmp_path / f"{target}.msh").stat().st_size > 0
    info = json.loads((tmp_path / f"{target}.json").read_text())
    assert (info["model"], info["level"], info["symmetry"]) == ("4", "coarse", "quarter")
    assert (tmp_path / "results/logs/mesh/quarter/model4_coarse.log").read_text().count("hole channels")
    assert (tmp_path / "results/benchmarks/mesh/quarter/model4_coarse.tsv").exists()


def test_local_runs_get_a_memory_budget(tmp_path):
    """A plain local `snakemake` holds the solves' mem_mb reservations against the machine's memory less
    study.memory_headroom_mb (the workflow profile is not found with the Snakefile at the root); an explicit
    `--resources mem_mb=...` wins."""
    wrapper = tmp_path / "Snakefile"
    wrapper.write_text(f'include: "{REPO / "Snakefile"}"\n'
                       'print("BUDGET", workflow.global_resources["mem_mb"].raw, file=sys.stderr)\n')
    with open("/proc/meminfo") as fh:
        total_mib = next(int(line.split()[1]) for line in fh if line.startswith("MemTotal:")) // 1024
    headroom = yaml.safe_load((REPO / "config/config.yaml").read_text())["study"]["memory_headroom_mb"]
    for extra, expected in (((), total_mib - headroom), (("--resources", "mem_mb=9000"), 9000)):
        run = _snakemake("-n", "--cores", "2", "-s", str(wrapper), "-d", str(REPO), *extra)
        assert run.returncode == 0, run.stderr[-3000:]
        budget = [line.split()[1] for line in run.stderr.splitlines() if line.startswith("BUDGET")]
        assert budget and int(budget[0]) == expected


def test_physical_memory_is_memtotal(tmp_path):
    """ureterfsi.workflow.machine.physical_memory_mib (the local budget's base): MemTotal in MiB; the kernel's count of
    physical pages on this machine; a file without MemTotal is named in the error."""
    import os

    import pytest

    from ureterfsi.workflow.machine import physical_memory_mib

    fake = tmp_path / "meminfo"
    fake.write_text("MemFree:  1024 kB\nMemTotal:  2048000 kB\n")
    assert physical_memory_mib(str(fake)) == 2000
    assert physical_memory_mib() == os.sysconf("SC_PHYS_PAGES") * os.sysconf("SC_PAGE_SIZE") // 2**20
    fake.write_text("MemFree:  1024 kB\n")
    with pytest.raises(ValueError, match="meminfo: no MemTotal"):
        physical_memory_mib(str(fake))


def test_a_fully_coupled_solve_given_less_memory_than_it_reserves_runs_out_of_core():
    """Rule solve passes --out-of-core 1 to a fully coupled run that reserves more than the local budget holds
    (config/reference.yaml's partitioned sweeps at the fine level, 26 000 MiB), so that MUMPS keeps its factors on
    disk; with a budget that holds its reservation, and for the coarse level, 0. A resource, not a param: another
    budget does not re-run a finished solve."""
    targets = [f"results/runs/fully_coupled/quarter/model3_{level}.nc" for level in ("coarse", "fine")]
    reference = yaml.safe_load((REPO / "config/reference.yaml").read_text())
    assert reference["solver"]["fully_coupled_scheme"] == "partitioned"
    reserved = yaml.safe_load((REPO / "config/config.yaml").read_text())["study"]["memory_mb"]["partitioned"]
    for budget in (reserved["fine"] - 1, reserved["fine"]):
        run = _snakemake("-n", "-p", "--forceall", "--cores", "2", "--resources", f"mem_mb={budget}",
                         "--configfile", "config/config.yaml", "config/reference.yaml", "--", *targets)
        assert run.returncode == 0, run.stderr[-3000:]
        commands = {level: [ln for ln in run.stdout.splitlines() if "-m ureterfsi.study" in ln and
                            f"--level {level} " in ln] for level in ("coarse", "fine")}
        assert all(len(c) == 1 for c in commands.values()), commands
        assert f"--out-of-core {int(budget < reserved['fine'])}" in commands["fine"][0], commands
        assert "--out-of-core 0" in commands["coarse"][0]
