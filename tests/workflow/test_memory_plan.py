"""Memory planning reads the ranks' own peak (ureterfsi.workflow.memory_plan): run files with and without the
per-rank record, their reservations, the suggested study.memory_mb entries and the refusal of a file without a
measured peak."""
from __future__ import annotations

import subprocess
import sys

import pytest
import xarray as xr

from ureterfsi.data.checked import BadFile
from ureterfsi.data.provenance import provenance_attrs
from ureterfsi.workflow import memory_plan
from ureterfsi.workflow.resources import solve_mem_mb


def run_file(path, cfg, fidelity, symmetry, level, processes, **peaks):
    ds = xr.Dataset({"outlet_flux": ("time", [0.0, 1.0])}, coords={"time": [0.0, 0.01]})
    ds.attrs.update(provenance_attrs(cfg, model="3", mesh_level=level, symmetry=symmetry, fidelity=fidelity,
                                     processes=processes, **peaks))
    ds.to_netcdf(path)
    return path


def test_a_run_measured_above_its_reservation_is_flagged_and_the_plan_covers_it(cfg, tmp_path):
    reserved = solve_mem_mb(cfg, "fully_coupled", "half", "medium")
    big = run_file(tmp_path / "fc.nc", cfg, "fully_coupled", "half", "medium", 2,
                   peak_memory_mib=3000.0, peak_memory_mib_all_ranks=reserved + 1000.0)
    small = run_file(tmp_path / "ow.nc", cfg, "one_way", "quarter", "coarse", 1, peak_memory_mib=2300.0)
    runs = [memory_plan.measured(cfg, big), memory_plan.measured(cfg, small)]
    assert runs[0].peak_mib == reserved + 1000.0          # the ranks' sum, not rank 0's own peak
    assert runs[0].over and not runs[1].over
    plan = memory_plan.suggested(cfg, runs, margin=1.25)
    half = cfg["study"]["memory_mb"]["symmetry_factor"]["half"]
    # the quarter-mesh entry that, times the half mesh's factor, covers the measured peak with the margin
    assert plan["fully_coupled"]["medium"] * half >= 1.25 * (reserved + 1000.0)
    assert plan["fully_coupled"]["medium"] % memory_plan.STEP_MIB == 0
    assert plan["one_way"] == {"coarse": 3000}             # 2300 x 1.25 = 2875, rounded up to 500 MiB


def test_a_multi_rank_run_without_the_ranks_record_is_refused_naming_the_file(cfg, tmp_path):
    old = run_file(tmp_path / "old.nc", cfg, "fully_coupled", "quarter", "fine", 2, peak_memory_mib=5000.0)
    with pytest.raises(BadFile, match="old.nc: no measured peak memory of all its ranks"):
        memory_plan.measured(cfg, old)


def test_the_command_line_prints_the_overlay_and_exits_1_on_an_under_reserved_run(cfg, repo_root, tmp_path):
    reserved = solve_mem_mb(cfg, "fully_coupled", "quarter", "coarse")
    path = run_file(tmp_path / "fc.nc", cfg, "fully_coupled", "quarter", "coarse", 2,
                    peak_memory_mib_all_ranks=reserved * 2.0)
    run = subprocess.run([sys.executable, "-m", "ureterfsi.workflow.memory_plan", "--config",
                          str(repo_root / "config" / "config.yaml"), "--runs", str(path)],
                         capture_output=True, text=True, cwd=tmp_path)
    assert run.returncode == 1, run.stderr
    assert "MORE THAN RESERVED" in run.stdout and "memory_mb:" in run.stdout and "fully_coupled:" in run.stdout
    path.write_bytes(b"CDF\x01 truncated")
    run = subprocess.run([sys.executable, "-m", "ureterfsi.workflow.memory_plan", "--config",
                          str(repo_root / "config" / "config.yaml"), "--runs", str(path)],
                         capture_output=True, text=True, cwd=tmp_path)
    assert run.returncode == 2 and str(path) in run.stderr and len(run.stderr.strip().splitlines()) == 1
