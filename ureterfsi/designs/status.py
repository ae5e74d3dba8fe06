"""Where a design study that runs in parts stands: each point's and reference's state (done, failed, resumable from
a checkpoint at time t, not started) and, once done, its key scalars (ureterfsi.designs.results.point_scalars).
Reads only the study's files under results/ (no solve, no Snakemake)::

    .venv/bin/python -m ureterfsi.designs.status config/config.yaml config/designs/occlusion_holes.yaml
"""
from __future__ import annotations

import argparse
import glob
import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ureterfsi.config import load_config_files
from ureterfsi.data.checked import BadFile
from ureterfsi.designs import expand
from ureterfsi.designs.results import point_scalars, read_run
from ureterfsi.designs.space import Study
from ureterfsi.workflow import paths

# the scalars of the table (ureterfsi.designs.results.point_scalars) and their units
COLUMNS = {"mean_outlet_flux": "m3/s", "hole_exchange_fraction": "1", "obstruction_lumen_fraction": "1",
           "peak_pelvic_pressure": "Pa", "reflux_volume_annulus": "m3", "reflux_volume_lumen": "m3",
           "stent_outer_low_wss_area_fraction": "1"}


@dataclass
class Entry:
    """One point or reference run of a study: its id, what it varies, its rung, its state and, once done, its
    scalars and its solve's CPU seconds."""
    id: str
    label: str
    rung: str
    state: str
    scalars: dict
    cpu_time: float


def checkpoint_time(study: str, point: str, root: Path) -> float | None:
    """Simulated time (s) of a point's restart checkpoint (any rank's), None without one."""
    files = sorted(glob.glob(str(root / paths.checkpoint(f"designs/{study}/{point}")).replace(".npz", "*.npz")))
    if not files:
        return None
    with np.load(files[0]) as data:
        try:
            return float(json.loads(str(data["meta"]))["time"])
        except (KeyError, ValueError) as err:
            raise BadFile(files[0], f"checkpoint without its meta record ({err})") from None


def entry(st: Study, point, label: str, root: Path) -> Entry:
    """The state of one point (or reference) of study `st` from its run file and checkpoint under `root`."""
    path = root / paths.design_run(st.name, point.id)
    if path.exists():
        run = read_run(path)
        if "solve_failed" in run.attrs:
            return Entry(point.id, label, point.rung, f"failed: {run.attrs['solve_failed']}", {}, np.nan)
        cpu = json.loads(run.attrs["cpu_time_s_per_rank"]) if "cpu_time_s_per_rank" in run.attrs else [np.nan]
        return Entry(point.id, label, point.rung, "done", point_scalars(run), float(np.sum(cpu)))
    t = checkpoint_time(st.name, point.id, root)
    state = "no run file, no checkpoint" if t is None else f"resumes at t = {t:g} s"
    return Entry(point.id, label, point.rung, state, {}, np.nan)


def study_status(cfg: dict, name: str, root: Path = Path(".")) -> list[Entry]:
    """The points (labelled by their parameter values) and references (by name) of study `name`."""
    st = expand.studies(cfg)[name]
    rows = [entry(st, p, ", ".join(f"{k}={v:g}" for k, v in p.values.items()), root) for p in st.points]
    return rows + [entry(st, p, f"reference {p.name}", root) for p in st.references]


def table(rows: list[Entry]) -> str:
    """A Markdown table of the entries: label, rung, state, the COLUMNS (SI units) and CPU seconds."""
    head = ["point", "rung", "state"] + [f"{c} ({u})" for c, u in COLUMNS.items()] + ["CPU (s)"]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for r in rows:
        vals = [f"{float(r.scalars[c]):.3g}" if c in r.scalars and np.isfinite(r.scalars[c]) else "-" for c in COLUMNS]
        cpu = f"{r.cpu_time:.0f}" if np.isfinite(r.cpu_time) else "-"
        lines.append("| " + " | ".join([r.label, r.rung, r.state] + vals + [cpu]) + " |")
    done = sum(r.state == "done" for r in rows)
    return "\n".join(lines + ["", f"{done} of {len(rows)} done"])


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("config", nargs="+", help="config file and overlays (as given to snakemake --configfile)")
    ap.add_argument("--study", help="the study's name (default: every study of the overlays)")
    ap.add_argument("--results-root", type=Path, default=Path("."), help="the folder holding results/")
    args = ap.parse_args(argv)
    if not (args.results_root / "results").is_dir():
        raise SystemExit(f"--results-root {args.results_root}: holds no results/ folder (give the folder that holds it)")
    cfg = load_config_files(args.config)
    for name in [args.study] if args.study else sorted(expand.studies(cfg)):
        print(f"## {name}\n\n{table(study_status(cfg, name, args.results_root))}\n")


if __name__ == "__main__":
    main()
