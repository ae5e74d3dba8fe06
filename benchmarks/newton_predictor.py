"""Newton's settings in a rung, side by side: by default the initial guess of the one-way urine solve, the
previous state ("constant") vs the linear and the quadratic extrapolation of the last two and three steps
(solver.predictor); `--setting solver.newton_field_rtol --values null 1e-6 1e-9` the per-field convergence test.

Runs the rung of one model on one study mesh over [0, end] once per value (separate processes, so that wall
times and peak memories do not mix), then reports per run the wall time, the Newton work (iterations,
factorisations, solves with a kept factorisation, time per phase) and the relative max-norm difference of every
figure quantity against the first value's run (ureterfsi.analyses.ladder.relative_error). Predictors stop at the same
Newton tolerance, so their difference must stay at the tolerance's level while the work drops; for a tolerance
the tightest value goes first, and the differences are the errors of the others.

    python benchmarks/newton_predictor.py --model 3 --level coarse --end 1.0
    python benchmarks/newton_predictor.py --config config/config.yaml config/segment-10mm.yaml \
        --mesh results/meshes/quarter/model3_coarse.msh --fidelity fully_coupled --end 0.08 \
        --setting solver.newton_field_rtol --values 1e-10 null 1e-6
"""
from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
from pathlib import Path

import xarray as xr
import yaml

from ureterfsi.config import load_config_files
from ureterfsi.workflow import paths as results
from ureterfsi.analyses.ladder import QUANTITIES, relative_error

ROOT = Path(__file__).resolve().parent.parent


def solve(cfg, args, value, out):
    cfg = json.loads(json.dumps(cfg))
    section, key = args.setting.split(".")
    cfg[section][key] = value
    with tempfile.NamedTemporaryFile("w", suffix=".json", delete=False) as fh:
        json.dump(cfg, fh)
    mesh = args.mesh or str(ROOT / results.mesh("quarter", args.model, args.level))
    r = subprocess.run([sys.executable, "-m", "ureterfsi.study", "--config-json", fh.name, "--model", args.model,
                        "--level", args.level, "--symmetry", "quarter", "--fidelity", args.fidelity, "--end",
                        str(args.end), "--mesh", mesh, "--out", str(out)], capture_output=True, text=True)
    Path(fh.name).unlink()
    if r.returncode:
        sys.exit(f"{args.setting} = {value}: the run failed (exit {r.returncode}): {r.stderr.strip()[-2000:]}")
    return xr.open_dataset(out, decode_times=False)


def parse(text: str):
    """A command-line value: a number (1e-6, which YAML 1.1 reads as a string) or YAML (null, linear)."""
    try:
        return float(text)
    except ValueError:
        return yaml.safe_load(text)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--config", nargs="+", default=[str(ROOT / "config/config.yaml")])
    ap.add_argument("--model", default="3")
    ap.add_argument("--level", default="coarse")
    ap.add_argument("--mesh", default=None, help="a study mesh (default results/meshes/quarter/model{M}_{level}.msh)")
    ap.add_argument("--fidelity", default="one_way", choices=["one_way", "fully_coupled"])
    ap.add_argument("--end", type=float, default=1.0, help="simulated time (s)")
    ap.add_argument("--setting", default="solver.predictor", help="section.key of the configuration to vary")
    ap.add_argument("--values", nargs="+", default=["constant", "linear", "quadratic"],
                    help="its values (YAML), the reference first")
    ap.add_argument("--workdir", default=None, help="where the runs are written (default: a temporary dir)")
    args = ap.parse_args()
    cfg = load_config_files(args.config)
    work = Path(args.workdir or tempfile.mkdtemp(prefix="newton_settings_"))
    work.mkdir(parents=True, exist_ok=True)
    runs = {v: solve(cfg, args, parse(v), work / f"run{i}.nc") for i, v in enumerate(args.values)}
    print(f"model {args.model}, {args.level} quarter mesh, {args.fidelity}, 0-{args.end} s, dt = {cfg['time']['dt']} s, "
          f"{args.setting} in {args.values}")
    print(f"{'value':10s} {'wall s':>8s} {'peak MiB':>9s} {'Newton':>7s}  counters / timings (s)")
    for v, ds in runs.items():
        print(f"{v:10s} {ds.attrs['wall_time_s']:8.1f} {ds.attrs['peak_memory_mib']:9.0f} "
              f"{int(ds['newton_iterations'].sum()):7d}  {ds.attrs['counters']} {ds.attrs['timings']}")
    first, *others = runs
    print(f"relative max-norm difference against {args.setting} = {first} ({', '.join(others)}):")
    for q in QUANTITIES:
        print(f"  {q:28s} " + " ".join(f"{relative_error(runs[first], runs[v], q):.2e}" for v in others))


if __name__ == "__main__":
    main()
