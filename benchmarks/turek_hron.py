#!/usr/bin/env python3
"""Turek-Hron FSI1 benchmark at several refinement levels: a table of dofs, Newton iterations, wall time,
point-A displacement, drag and lift and their relative errors against Turek & Hron (2006).

    .venv/bin/python benchmarks/turek_hron.py                  # refinements 0.5 1 2
    .venv/bin/python benchmarks/turek_hron.py --levels 1 2 4 --json fsi1.json

Element size on the obstacle is 0.008/refinement m, in the far field 0.04/refinement m (P2/P2/P1).
Drag and lift: variational (residual) force; "trac" columns: boundary integral of the fluid traction.
"""
from __future__ import annotations

import argparse
import json
import sys
from dataclasses import asdict
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from mpi4py import MPI  # noqa: E402

from ureterfsi.scenes import turek_hron as th  # noqa: E402


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--levels", type=float, nargs="+", default=[0.5, 1.0, 2.0], help="refinement factors")
    ap.add_argument("--json", help="write the results to this file")
    args = ap.parse_args(argv)
    comm = MPI.COMM_WORLD
    results = []
    for level in args.levels:
        res = th.run_fsi1(level, comm)
        results.append(res)
        if comm.rank == 0:
            print(f"refinement {level:g}: {res.dofs} dofs, {res.newton_iterations} Newton iterations, "
                  f"setup {res.setup_time:.1f} s, solve {res.solve_time:.1f} s", flush=True)
    if comm.rank == 0:
        ref = th.REFERENCE_FSI1
        head = (f"{'refine':>6} {'cells':>6} {'dofs':>7} {'newton':>6} {'wall[s]':>8} "
                f"{'ux(A)[m]':>11} {'err%':>6} {'uy(A)[m]':>11} {'err%':>6} "
                f"{'drag[N/m]':>9} {'err%':>6} {'lift[N/m]':>9} {'err%':>6} {'drag_trac':>9} {'lift_trac':>9}")
        print(f"\nTurek-Hron FSI1 (MPI ranks: {comm.size})")
        print(head)
        print("-" * len(head))
        for r in results:
            e = r.errors
            print(f"{r.refinement:6g} {r.cells:6d} {r.dofs:7d} {r.newton_iterations:6d} {r.wall_time:8.1f} "
                  f"{r.ux_A:11.4e} {100 * e['ux_A']:6.3f} {r.uy_A:11.4e} {100 * e['uy_A']:6.3f} "
                  f"{r.drag:9.4f} {100 * e['drag']:6.3f} {r.lift:9.5f} {100 * e['lift']:6.3f} "
                  f"{r.drag_boundary:9.4f} {r.lift_boundary:9.5f}")
        print(f"{'ref':>6} {'':6} {'':7} {'':6} {'':8} {ref['ux_A']:11.4e} {'':6} {ref['uy_A']:11.4e} {'':6} "
              f"{ref['drag']:9.4f} {'':6} {ref['lift']:9.5f}")
        if args.json:
            Path(args.json).write_text(json.dumps({"reference": ref, "results": [asdict(r) for r in results]},
                                                  indent=2, default=str) + "\n")
    return results


if __name__ == "__main__":
    main()
