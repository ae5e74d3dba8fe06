"""Build, step and release a tube problem (tests/helpers/engine_cases.py) ten times, cycling through the whole-system LU,
the partitioned and the block Gauss-Seidel strategies; after each, print one JSON line: PETSc's live objects per
class (creations minus destructions, from PETSc's own log) and the process's resident memory in MiB.

    python tests/helpers/release_driver.py close|drop

close: MonolithicFSI.close() in a with-block; drop: the last reference dropped (collected on one process).
Used by tests/fsi/test_release.py (a process of its own: PETSc's log, once begun, stays on).
"""
from __future__ import annotations

import gc
import json
import os
import re
import sys
import tempfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
sys.path.insert(0, str(Path(__file__).resolve().parents[2]))

from petsc4py import PETSc  # noqa: E402

from helpers.engine_cases import tube_problem  # noqa: E402
from ureterfsi.fsi import SolverOptions  # noqa: E402

STRATEGIES = ({}, {"coupling_scheme": "partitioned"}, {"linear_solver": "block_gauss_seidel"})
MESH = {"n_fluid": 8, "n_wall": 4, "n_axial": 160}


def live_objects() -> dict:
    """{PETSc class: objects created and not destroyed} since PETSc.Log.begin(), from PETSc.Log.view's table."""
    fd, path = tempfile.mkstemp(suffix=".txt")
    os.close(fd)
    viewer = PETSc.Viewer().createASCII(path)
    PETSc.Log.view(viewer)
    viewer.destroy()
    text = Path(path).read_text()
    os.remove(path)
    table = text[text.index("Object Type"):]
    table = table[:table.index("=" * 20)]
    live = {}
    for name, created, destroyed in re.findall(r"^\s+(\S.*?)\s+(\d+)\s+(\d+)\s*$", table, re.M):
        live[name] = live.get(name, 0) + int(created) - int(destroyed)
    live.pop("Viewer", None)              # this function's own
    return {k: v for k, v in live.items() if v}


def resident_mib() -> float:
    with open("/proc/self/status") as status:
        return next(int(line.split()[1]) for line in status if line.startswith("VmRSS:")) / 1024


def main(mode: str) -> None:
    PETSc.Log.begin()
    for i in range(10):
        pb, _ = tube_problem(options=SolverOptions(**STRATEGIES[i % len(STRATEGIES)]), **MESH)
        if mode == "close":
            with pb:
                pb.solve_steady()
                pb.step(2e-3)
        else:
            pb.solve_steady()
            pb.step(2e-3)
        del pb
        gc.collect()
        print(json.dumps({"live": live_objects(), "rss_mib": resident_mib()}), flush=True)


if __name__ == "__main__":
    main(sys.argv[1])
