"""A released problem leaves neither PETSc objects nor memory behind (fsi.release, MonolithicFSI.close).

tests/helpers/release_driver.py builds, steps and releases a tube problem ten times (whole-system LU, partitioned and
block Gauss-Seidel strategies in turn, 38 033 unknowns, ~75 MiB of matrices and factors each) in a process of
its own, reading PETSc's live objects per class from PETSc's log after each: they and the resident memory must
stay flat. Before close() and the garbage collection of fsi.release, every problem left its matrices, KSPs and
LU factors alive (petsc4py 3.18 stashes what Python collects in the communicator's garbage) and the process grew
by ~75 MiB per problem.
"""
import json
import subprocess
import sys
from pathlib import Path

import pytest

DRIVER = Path(__file__).resolve().parents[1] / "helpers" / "release_driver.py"
RSS_GROWTH_MIB = 40.0        # from the 3rd to the 10th problem; a leaking strategy alone leaks ~150 MiB there


@pytest.mark.parametrize("mode", ["close", "drop"])
def test_ten_problems_built_and_released_leave_petsc_objects_and_memory_flat(mode):
    out = subprocess.run([sys.executable, str(DRIVER), mode], capture_output=True, text=True, check=True).stdout
    rows = [json.loads(line) for line in out.splitlines() if line.startswith("{")]
    assert len(rows) == 10
    assert all(row["live"] == rows[0]["live"] for row in rows), [row["live"] for row in rows]
    growth = rows[-1]["rss_mib"] - rows[2]["rss_mib"]
    assert growth < RSS_GROWTH_MIB, [round(row["rss_mib"]) for row in rows]


HELD_AT_EXIT = """
import sys
import netCDF4  # noqa: F401  (before dolfinx)
from ureterfsi.fsi import MonolithicFSI, OpenBoundary, SolverOptions
from ureterfsi.scenes.rigid_pipe import INLET, OUTLET, RigidPipe, rigid_pipe_scene
pb = MonolithicFSI(rigid_pipe_scene(RigidPipe(), 4, OpenBoundary([INLET], 0.0), OpenBoundary([OUTLET], 0.0)),
                   SolverOptions())
pb.A
sys.exit("error: the solve failed during set-up")
"""


def test_a_problem_held_when_a_failed_solve_exits_says_nothing_more():
    """A solve that fails after building its problem exits with its one-line message alone: the problem, still
    held while the interpreter shuts down, is not closed then (petsc4py can no longer reach MPI; it printed an
    ignored ImportError from MonolithicFSI.__del__)."""
    proc = subprocess.run([sys.executable, "-c", HELD_AT_EXIT], capture_output=True, text=True)
    assert proc.returncode == 1
    assert proc.stderr.strip() == "error: the solve failed during set-up", proc.stderr
