"""Snakemake mesh rules (paper §2.4.1): dry run of the default target, one coarse mesh built by the workflow."""
import json
import subprocess
import sys
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent


def _snakemake(*args, cwd=REPO):
    return subprocess.run([sys.executable, "-m", "snakemake", *args], cwd=cwd, capture_output=True, text=True,
                          timeout=600)


def test_dry_run_of_default_target():
    run = _snakemake("-n", "--forceall", "--cores", "2")
    assert run.returncode == 0, run.stderr[-3000:]
    assert "rule mesh:" in run.stdout


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
