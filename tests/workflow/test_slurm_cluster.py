"""The SLURM profile on a real SLURM (tests/slurm/cluster.sh brings one up on this machine; .ci/run runs this file
under it): the shipped workflow/profiles/slurm with only a site overlay (tests/slurm/site.yaml: partition, time
limit, node size) on the e2e configuration (the 10 mm segment, 2 steps of 20 ms). The mesh, the wall motion, a
one-way solve and a fully coupled solve on 2 ranks under srun run as SLURM jobs and their run files are written;
the fully coupled run's own record says 2 processes, with their CPU times and summed peak memory; a job made to
fail (its mesh truncated) is reported as failed: Snakemake exits non-zero and names the job's output.
Without a cluster (SLURM_CONF unset) that test is skipped; under tests/slurm/cluster.sh it cannot skip.
Without a cluster too: the site overlay's caps and refusal in a dry run (the plugin submits nothing)."""
from __future__ import annotations

import json
import os
import shutil
import subprocess
import time
from pathlib import Path

import sys

import pytest
import xarray as xr

from helpers.snakemake_runs import REPO, SLURM_PROFILE, e2e_config, ok, planned_jobs

SITE = REPO / "tests" / "slurm" / "site.yaml"
COUPLED = "results/runs/fully_coupled/quarter/model2_coarse.nc"
ONE_WAY = "results/runs/one_way/quarter/model2_coarse.nc"



def slurm_snakemake(work: Path, cfg_path: Path, *args, timeout: int, overlays=(SITE,)):
    """The README's cluster command: the shipped profile, the configuration and the site overlay last; the
    environment without USER, as in CI containers and some batch environments."""
    cmd = [sys.executable, "-m", "snakemake", "--snakefile", str(REPO / "Snakefile"), "--directory", str(work),
           "--workflow-profile", str(SLURM_PROFILE), *map(str, args), "--configfile", str(cfg_path), *map(str, overlays)]
    env = {k: v for k, v in os.environ.items() if k != "USER"}
    return subprocess.run(cmd, cwd=REPO, capture_output=True, text=True, timeout=timeout, env=env)


def test_site_overlay_caps_every_job_and_refuses_what_cannot_fit(tmp_path):
    """Dry runs of the README's cluster command: with the CI's site (2 cores, 6000 MiB, 60 min, partition ci)
    every job asks at most that, in that partition, and exports SLURM_MPI_TYPE=pmix; the fully coupled solve on
    2 ranks keeps its factors on disk. A one-way solve that needs more than a smaller node has is refused in one
    line naming the run, study.memory_mb and cluster.mem_mb_per_node, and nothing is planned."""
    cfg_path = tmp_path / "e2e-config.yaml"
    e2e_config(cfg_path)
    work = tmp_path / "slurm"
    work.mkdir()
    out = ok(slurm_snakemake(work, cfg_path, COUPLED, ONE_WAY, "-n", "-p", timeout=300))
    jobs = [j for j in planned_jobs(out) if j["resources"]]
    assert {"mesh", "wall_motion", "solve"} <= {j["rule"] for j in jobs}, jobs
    for j in jobs:
        r = j["resources"]
        assert int(r["mem_mb"]) <= 6000 and int(r["runtime"]) <= 60 and int(r.get("tasks", 1)) <= 2, j
        assert r["slurm_partition"] == "ci" and r["slurm_extra"] == "--export=ALL,SLURM_MPI_TYPE=pmix", j
    coupled = next(j for j in jobs if j["output"] == COUPLED)
    assert coupled["resources"]["tasks"] == "2" and coupled["resources"]["mumps_out_of_core"] == "1", coupled
    assert coupled["shell"].startswith("srun -n 2 "), coupled

    small = tmp_path / "small-node.yaml"
    small.write_text("cluster: {mem_mb_per_node: 3000}\n")
    run = slurm_snakemake(work, cfg_path, ONE_WAY, "-n", timeout=300, overlays=(SITE, small))
    assert run.returncode != 0
    assert (f"{ONE_WAY} needs 6000 MiB (study.memory_mb), more than a node has (cluster.mem_mb_per_node: 3000)"
            in run.stdout + run.stderr), run.stdout[-3000:] + run.stderr[-3000:]


@pytest.mark.skipif("SLURM_CONF" not in os.environ, reason="no SLURM (tests/slurm/cluster.sh)")
def test_profile_runs_on_slurm(tmp_path):
    assert shutil.which("sbatch") and subprocess.run(["sinfo"], capture_output=True).returncode == 0
    cfg_path = tmp_path / "e2e-config.yaml"
    e2e_config(cfg_path)
    work = tmp_path / "slurm"
    work.mkdir()
    t0 = time.perf_counter()
    run = slurm_snakemake(work, cfg_path, COUPLED, ONE_WAY, timeout=1800)
    print(f"\nSLURM run (mesh, wall motion, one-way and 2-rank fully coupled solves): "
          f"{time.perf_counter() - t0:.0f} s")
    out = ok(run)
    assert "srun -n 2 " in out, out[-3000:]
    for target in (COUPLED, ONE_WAY):
        assert (work / target).exists(), target
    with xr.open_dataset(work / COUPLED, decode_times=False) as ds:
        attrs = dict(ds.attrs)
    assert attrs["processes"] == 2, attrs
    cpu = json.loads(attrs["cpu_time_s_per_rank"])
    assert len(cpu) == 2 and min(cpu) > 0, cpu
    assert attrs["peak_memory_mib_all_ranks"] > 2 * 100, attrs        # two dolfinx processes

    # a job made to fail: the one-way solve on a truncated mesh
    mesh = work / "results/meshes/quarter/model2_coarse.msh"
    mesh.write_text(mesh.read_text()[:1000])
    t0 = time.perf_counter()
    run = slurm_snakemake(work, cfg_path, ONE_WAY, "--forcerun", "solve", timeout=900)
    print(f"SLURM failing job reported after {time.perf_counter() - t0:.0f} s")
    log = run.stdout + run.stderr
    assert run.returncode != 0 and "Error in rule solve" in log and ONE_WAY in log, log[-3000:]
