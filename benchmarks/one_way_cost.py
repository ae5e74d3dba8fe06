"""The one-way rung's cost, two versions side by side: two clones of the project (`--old DIR`: today's code against
this one) or two configurations of this one (`--overlays A.yaml B.yaml`). Both solves run at once, one process each,
so that they see the same machine (its speed varies 2-3x over a day); each pair is one ratio. Reported per run: CPU
time (user + system, from the operating system's accounting of the finished process), wall time, peak memory,
Newton iterations, LU factorisations; per pair the CPU-time ratio B/A; and the relative max-norm difference of
every figure quantity of B against A (ureterfsi.ladder.relative_error). The CPU time includes the set-up (reading
the mesh, compiling forms not yet in the cache: run a short window first to fill it).

    python benchmarks/one_way_cost.py --old ../old-clone --end 3.0
    python benchmarks/one_way_cost.py --overlays none linearly_implicit.yaml --end 0.6 --pairs 2

The mesh and the wall motion are this clone's results/ (snakemake results/meshes/quarter/model3_coarse.msh
results/runs/one_way/wall_motion.nc), read by both.
"""
from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import xarray as xr

from ureterfsi.analyses.ladder import QUANTITIES, relative_error

ROOT = Path(__file__).resolve().parent.parent


def start(clone: Path, overlay: str, args, out: Path):
    """The solve as a child process in `clone` (its own package and config/config.yaml, plus `overlay`)."""
    configs = [str(clone / "config/config.yaml")] + ([] if overlay == "none" else [str(Path(overlay).resolve())])
    mesh = args.mesh or str(ROOT / f"results/meshes/quarter/model{args.model}_{args.level}.msh")
    cmd = [sys.executable, "-m", "ureterfsi.study", "--config", *configs, "--model", args.model, "--level",
           args.level, "--symmetry", "quarter", "--fidelity", "one_way", "--end", str(args.end), "--mesh", mesh,
           "--wall", args.wall or str(ROOT / "results/runs/one_way/wall_motion.nc"), "--out", str(out)]
    log = open(out.with_suffix(".log"), "w")
    return subprocess.Popen(cmd, cwd=clone, stdout=log, stderr=subprocess.STDOUT), time.perf_counter()


def wait(procs) -> list:
    """[(CPU s, wall s, peak RSS MiB)] of the children (Popen, start time), in their order, as each finishes; exits on
    a failed solve."""
    done = {}
    while len(done) < len(procs):
        pid, status, usage = os.wait4(-1, 0)
        k = next(i for i, (p, _) in enumerate(procs) if p.pid == pid)
        if os.waitstatus_to_exitcode(status):
            sys.exit(f"a solve failed (exit {os.waitstatus_to_exitcode(status)}): {procs[k][0].args}")
        done[k] = (usage.ru_utime + usage.ru_stime, time.perf_counter() - procs[k][1], usage.ru_maxrss / 1024)
    return [done[k] for k in range(len(procs))]


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--old", default=None, help="clone of the code A (default: this one)")
    ap.add_argument("--overlays", nargs=2, default=["none", "none"], help="config overlays of A and B ('none')")
    ap.add_argument("--model", default="3")
    ap.add_argument("--level", default="coarse")
    ap.add_argument("--mesh", default=None, help="default: this clone's results/meshes/quarter/model{M}_{level}.msh")
    ap.add_argument("--wall", default=None, help="default: this clone's results/runs/one_way/wall_motion.nc")
    ap.add_argument("--end", type=float, default=3.0, help="simulated time (s)")
    ap.add_argument("--pairs", type=int, default=1, help="pairs of side-by-side runs")
    ap.add_argument("--workdir", default=None)
    args = ap.parse_args()
    work = Path(args.workdir or tempfile.mkdtemp(prefix="one_way_cost_"))
    work.mkdir(parents=True, exist_ok=True)
    clones = [Path(args.old or ROOT).resolve(), ROOT]
    print(f"model {args.model}, {args.level} quarter mesh, one-way, 0-{args.end} s; A = {clones[0]} "
          f"({args.overlays[0]}), B = {clones[1]} ({args.overlays[1]}); runs in {work}")
    for k in range(args.pairs):
        outs = [work / f"pair{k}_{name}.nc" for name in "AB"]
        procs = [start(c, o, args, out) for c, o, out in zip(clones, args.overlays, outs)]
        (cpu_a, wall_a, mem_a), (cpu_b, wall_b, mem_b) = wait(procs)
        runs = [xr.open_dataset(out, decode_times=False) for out in outs]
        for name, ds, cpu, wall, mem in zip("AB", runs, (cpu_a, cpu_b), (wall_a, wall_b), (mem_a, mem_b)):
            print(f"pair {k} {name}: CPU {cpu:7.1f} s  wall {wall:7.1f} s  peak {mem:6.0f} MiB  Newton "
                  f"{int(ds['newton_iterations'].sum())}  {ds.attrs['counters']}  {ds.attrs['timings']}")
        print(f"pair {k}: CPU time B/A = {cpu_b / cpu_a:.3f}, wall time B/A = {wall_b / wall_a:.3f}")
        print("  relative max-norm difference of B against A:")
        for q in QUANTITIES:
            print(f"    {q:28s} {relative_error(runs[0], runs[1], q):.2e}")


if __name__ == "__main__":
    main()
