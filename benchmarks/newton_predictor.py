"""Newton's initial guess in the one-way urine solve: the previous state ("constant") vs the linear and the
quadratic extrapolation of the last two and three steps ("linear", "quadratic"; solver.predictor).

Runs the one-way rung of one model on one study mesh over [0, end] once per predictor (separate processes,
so that wall times and peak memories do not mix), then reports per run the wall time, the Newton work
(factorisations, solves with a kept factorisation, time per phase) and the relative max-norm difference of
every figure quantity against the constant predictor's run (ureterfsi.ladder.relative_error): all stop at the same absolute
Newton tolerance, so the difference must stay at the tolerance's level while the work drops.

    python benchmarks/newton_predictor.py --model 3 --level coarse --end 1.0
"""
from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
from pathlib import Path

import xarray as xr

from ureterfsi.config import load_config_files
from ureterfsi.ladder import QUANTITIES, relative_error

ROOT = Path(__file__).resolve().parent.parent


def solve(cfg, model, level, end, predictor, out):
    cfg = json.loads(json.dumps(cfg))
    cfg["solver"]["predictor"] = predictor
    with tempfile.NamedTemporaryFile("w", suffix=".json", delete=False) as fh:
        json.dump(cfg, fh)
    subprocess.run([sys.executable, "-m", "ureterfsi.study", "--config-json", fh.name, "--model", model,
                    "--level", level, "--symmetry", "quarter", "--fidelity", "one_way", "--end", str(end),
                    "--mesh", str(ROOT / f"results/meshes/quarter/model{model}_{level}.msh"), "--out", str(out)],
                   check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    Path(fh.name).unlink()
    return xr.open_dataset(out, decode_times=False)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--config", nargs="+", default=[str(ROOT / "config/config.yaml")])
    ap.add_argument("--model", default="3")
    ap.add_argument("--level", default="coarse")
    ap.add_argument("--end", type=float, default=1.0, help="simulated time (s)")
    ap.add_argument("--workdir", default=None, help="where the two runs are written (default: a temporary dir)")
    args = ap.parse_args()
    cfg = load_config_files(args.config)
    work = Path(args.workdir or tempfile.mkdtemp(prefix="newton_predictor_"))
    work.mkdir(parents=True, exist_ok=True)
    runs = {p: solve(cfg, args.model, args.level, args.end, p, work / f"{p}.nc")
            for p in ("constant", "linear", "quadratic")}
    print(f"model {args.model}, {args.level} quarter mesh, one-way, 0-{args.end} s, dt = {cfg['time']['dt']} s")
    print(f"{'predictor':10s} {'wall s':>8s} {'peak MiB':>9s}  counters / timings (s)")
    for p, ds in runs.items():
        print(f"{p:10s} {ds.attrs['wall_time_s']:8.1f} {ds.attrs['peak_memory_mib']:9.0f}  "
              f"{ds.attrs['counters']} {ds.attrs['timings']}")
    print("relative max-norm difference against the constant predictor (linear, quadratic):")
    for q in QUANTITIES:
        print(f"  {q:28s} {relative_error(runs['constant'], runs['linear'], q):.2e} "
              f"{relative_error(runs['constant'], runs['quadratic'], q):.2e}")


if __name__ == "__main__":
    main()
