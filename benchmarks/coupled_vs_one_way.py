"""The fully coupled rung against the one-way rung, side by side on one machine (issue: the fully coupled model at
no more than 3x the one-way cost): both solves of one model and mesh level start together, each as its own process
(`python -m ureterfsi.study`, the solve rule's command), and the table gives each one's CPU time (user + system,
from the kernel's accounting of the child), wall time and peak RSS, their ratios, and the one-way rung's errors
against the fully coupled run (ureterfsi.analyses.ladder.relative_error, relative max norm per figure quantity). Each solve
runs with the thread count the solve rule gets (`threads: 1`: Snakemake sets OMP_NUM_THREADS, OPENBLAS_NUM_THREADS,
... to the rule's threads), so MUMPS's OpenMP and BLAS threads do not spin on the other solve's core.

    python benchmarks/coupled_vs_one_way.py --out /tmp/cvo                          # model 3, coarse, 3 s
    python benchmarks/coupled_vs_one_way.py --level medium --end 1.0 --out /tmp/cvo_medium
    python benchmarks/coupled_vs_one_way.py --from-dir /tmp/cvo                     # table of an earlier run

The mesh, the run configuration and the r-z wall motion come from the workflow (`snakemake --cores 1 ...` with the
given configuration files); the fully coupled solve checkpoints into OUT (a killed benchmark resumes). Results:
OUT/{fully_coupled,one_way}.nc, their logs, OUT/benchmark.json.
"""
from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time
from pathlib import Path

from ureterfsi.workflow import paths as results

ROOT = Path(__file__).resolve().parent.parent
RUNGS = ("fully_coupled", "one_way")
THREAD_VARIABLES = ("OMP_NUM_THREADS", "GOTO_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS",
                    "VECLIB_MAXIMUM_THREADS", "NUMEXPR_NUM_THREADS")  # those Snakemake's shell sets to `threads`


def prerequisites(configs: list[str], model: str, level: str, symmetry: str) -> dict:
    """Make (through the workflow) and return the paths of the mesh, the run configuration and the wall motion."""
    paths = {"mesh": results.mesh(symmetry, model, level), "config": results.run_config(model),
             "wall": results.WALL_MOTION}
    subprocess.run([sys.executable, "-m", "snakemake", *paths.values(), "--cores", "1", "--quiet", "progress",
                    "--configfile", *configs], cwd=ROOT, check=True)
    return {k: str(ROOT / v) for k, v in paths.items()}


def launch(rung: str, paths: dict, args, out: Path) -> tuple[subprocess.Popen, float]:
    cmd = [sys.executable, "-m", "ureterfsi.study", "--run-config", paths["config"], "--model", args.model,
           "--level", args.level, "--symmetry", args.symmetry, "--fidelity", rung, "--mesh", paths["mesh"],
           "--out", str(out / f"{rung}.nc"), "--end", str(args.end), "--dt", str(args.dt)]
    cmd += ["--checkpoint", str(out / f"{rung}.ckpt")] if rung == "fully_coupled" else ["--wall", paths["wall"]]
    log = open(out / f"{rung}.log", "w")
    env = os.environ | dict.fromkeys(THREAD_VARIABLES, str(args.threads))
    return subprocess.Popen(cmd, cwd=ROOT, env=env, stdout=log, stderr=subprocess.STDOUT), time.perf_counter()


def run(args) -> dict:
    out = Path(args.out).resolve()
    out.mkdir(parents=True, exist_ok=True)
    paths = prerequisites(args.configfile, args.model, args.level, args.symmetry)
    procs = {rung: launch(rung, paths, args, out) for rung in RUNGS}
    cost = {}
    while procs:
        pid, status, usage = os.wait4(-1, 0)
        rung = next(r for r, (p, _) in procs.items() if p.pid == pid)
        started = procs.pop(rung)[1]
        if os.waitstatus_to_exitcode(status) != 0:
            for p, _ in procs.values():
                p.terminate()
            sys.exit(f"{rung} solve failed (exit {os.waitstatus_to_exitcode(status)}): see {out / (rung + '.log')}")
        cost[rung] = {"cpu_s": usage.ru_utime + usage.ru_stime, "user_s": usage.ru_utime,
                      "wall_s": time.perf_counter() - started, "peak_gib": usage.ru_maxrss / 2**20}
    result = {"model": args.model, "level": args.level, "symmetry": args.symmetry, "end": args.end, "dt": args.dt,
              "threads": args.threads, "cost": cost}
    (out / "benchmark.json").write_text(json.dumps(result, indent=1))
    return result


def table(out: Path) -> str:
    import netCDF4  # noqa: F401  (the netCDF4 engine before xarray)
    import xarray as xr

    from ureterfsi.analyses.ladder import QUANTITIES, relative_error

    result = json.loads((out / "benchmark.json").read_text())
    cost = result["cost"]
    runs = {rung: xr.open_dataset(out / f"{rung}.nc", decode_times=False) for rung in RUNGS}
    fc, ow = (cost[r] for r in RUNGS)
    sweeps = json.loads(runs["fully_coupled"].attrs.get("counters", "{}")).get("sweeps")
    lines = [f"model {result['model']}, {result['level']} {result['symmetry']}, 0-{result['end']} s at dt = "
             f"{result['dt']} s, {result.get('threads', 'default')} thread(s) per solve; fully coupled: "
             f"{runs['fully_coupled'].attrs.get('dofs')} unknowns, {sweeps} sweeps",
             "", "| rung | CPU s (user) | wall s | peak |", "|---|---|---|---|"]
    lines += [f"| {r} | {cost[r]['cpu_s']:.0f} ({cost[r]['user_s']:.0f}) | {cost[r]['wall_s']:.0f} | "
              f"{cost[r]['peak_gib']:.2f} GiB |" for r in RUNGS]
    lines += [f"| ratio | {fc['cpu_s'] / ow['cpu_s']:.2f}x ({fc['user_s'] / ow['user_s']:.2f}x) | "
              f"{fc['wall_s'] / ow['wall_s']:.2f}x | {fc['peak_gib'] / ow['peak_gib']:.2f}x |", "",
              "| quantity | one-way error |", "|---|---|"]
    extra = [v for v in ("outlet_lumen_flux", "inlet_lumen_flux") if v in runs["fully_coupled"]]
    lines += [f"| {q} | {relative_error(runs['fully_coupled'], runs['one_way'], q):.2e} |"
              for q in (*QUANTITIES, *extra) if q in runs["fully_coupled"]]
    return "\n".join(lines)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--configfile", nargs="+", default=["config/config.yaml", "config/ladder-pulse.yaml"])
    ap.add_argument("--model", default="3")
    ap.add_argument("--level", default="coarse")
    ap.add_argument("--symmetry", default="quarter")
    ap.add_argument("--end", type=float, default=3.0, help="simulated time [s]")
    ap.add_argument("--dt", type=float, default=0.01, help="time step [s]")
    ap.add_argument("--threads", type=int, default=1, help="threads per solve (the solve rule's)")
    ap.add_argument("--out", help="directory of the runs")
    ap.add_argument("--from-dir", help="no run: the table of an earlier --out directory")
    args = ap.parse_args()
    if args.from_dir:
        print(table(Path(args.from_dir)))
        return
    if not args.out:
        ap.error("--out or --from-dir")
    run(args)
    print(table(Path(args.out).resolve()))


if __name__ == "__main__":
    main()
