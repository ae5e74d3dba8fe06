"""Memory planning from what the solves measured themselves: each run file's peak resident memory summed over
its ranks (attribute ``peak_memory_mib_all_ranks``, ureterfsi.study.pipeline.rank_usage; a batch system's record
of an ``srun`` job step measures its client, not the ranks) against the reservation ``study.memory_mb`` gives
that run (resources.solve_mem_mb), and the ``study.memory_mb`` entries that would cover every measured run.

    python -m ureterfsi.workflow.memory_plan --config config/config.yaml [OVERLAY ...] --runs RUN.nc ...

prints one line per run and the suggested entries as a configuration overlay; exits 1 when a run measured more
than its reservation (a job of that size would be killed on a cluster that enforces mem_mb).
"""
from __future__ import annotations

import argparse
import math
import sys
from dataclasses import dataclass

import yaml

from ..config import ConfigError, load_config_files
from ..data.checked import BadFile, Contract, open_netcdf
from .resources import memory_entry, solve_mem_mb

RUN_FILE = Contract("run file", attrs=("model", "mesh_level", "symmetry", "fidelity"))
STEP_MIB = 500          # suggested reservations are rounded up to this


@dataclass(frozen=True)
class Measured:
    """One run's measured peak (MiB, summed over its ranks) beside its reservation (MiB)."""
    path: str
    fidelity: str
    symmetry: str
    level: str
    processes: int
    peak_mib: float
    reserved_mib: int

    @property
    def over(self) -> bool:
        return self.peak_mib > self.reserved_mib


def peak_of(path, attrs: dict) -> float:
    """The run's peak over all ranks (MiB); a serial run written before the per-rank record holds only
    ``peak_memory_mib`` (its one process). BadFile naming the file when neither is there."""
    if "peak_memory_mib_all_ranks" in attrs:
        return float(attrs["peak_memory_mib_all_ranks"])
    if "peak_memory_mib" in attrs and int(attrs.get("processes", 1)) == 1:
        return float(attrs["peak_memory_mib"])
    raise BadFile(path, "no measured peak memory of all its ranks (attribute 'peak_memory_mib_all_ranks'): "
                        "written before the solves recorded it; re-run the solve")


def measured(cfg: dict, path) -> Measured:
    """The measured peak of the run file at `path` and the reservation `cfg` gives a run of its kind."""
    ds = open_netcdf(path, RUN_FILE)
    a = ds.attrs
    fidelity, symmetry, level = str(a["fidelity"]), str(a["symmetry"]), str(a["mesh_level"])
    return Measured(str(path), fidelity, symmetry, level, int(a.get("processes", 1)), peak_of(path, a),
                    solve_mem_mb(cfg, fidelity, symmetry, level))


def suggested(cfg: dict, runs: list[Measured], margin: float) -> dict:
    """study.memory_mb entries covering every measured run with `margin` (e.g. 1.25 = 25 % above the peak),
    rounded up to STEP_MIB: a 3D run's peak divided by its symmetry's factor gives the quarter-mesh entry of its
    fidelity (by `cfg`'s scheme, resources.memory_entry) and level (the table's convention); an r-z run gives
    `axisymmetric`. Only entries that measured runs inform; the largest of the current entry's runs wins."""
    factors = cfg["study"]["memory_mb"]["symmetry_factor"]
    out: dict = {}
    for r in runs:
        need = STEP_MIB * math.ceil(r.peak_mib * margin / STEP_MIB)
        if r.symmetry == "axisymmetric":
            out["axisymmetric"] = max(out.get("axisymmetric", 0), need)
            continue
        quarter = STEP_MIB * math.ceil(r.peak_mib * margin / factors[r.symmetry] / STEP_MIB)
        table = out.setdefault(memory_entry(r.fidelity, cfg["solver"]["fully_coupled_scheme"]), {})
        table[r.level] = max(table.get(r.level, 0), quarter)
    return out


def report(runs: list[Measured], plan: dict) -> str:
    lines = [f"{'run file':60s} {'ranks':>5s} {'peak MiB':>9s} {'reserved':>9s}"]
    for r in runs:
        flag = "  MORE THAN RESERVED" if r.over else ""
        lines.append(f"{r.path:60s} {r.processes:5d} {r.peak_mib:9.0f} {r.reserved_mib:9d}{flag}")
    lines.append("# suggested reservations (an overlay; quarter-mesh entries, MiB):")
    lines.append(yaml.safe_dump({"study": {"memory_mb": plan}}, sort_keys=True).rstrip())
    return "\n".join(lines)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python -m ureterfsi.workflow.memory_plan", description=__doc__.split("\n")[0])
    ap.add_argument("--config", nargs="+", required=True, help="configuration file and overlays, in order")
    ap.add_argument("--runs", nargs="+", required=True, help="run files (results/runs/...)")
    ap.add_argument("--margin", type=float, default=1.25, help="reservation / measured peak (default 1.25)")
    args = ap.parse_args(argv)
    if not args.margin >= 1.0:
        ap.error(f"--margin {args.margin}: must be >= 1 (a reservation below the measured peak)")
    try:
        cfg = load_config_files(args.config)
        runs = [measured(cfg, p) for p in args.runs]
    except (BadFile, ConfigError) as err:
        print(f"error: {err}", file=sys.stderr)
        return 2
    print(report(runs, suggested(cfg, runs, args.margin)))
    return 1 if any(r.over for r in runs) else 0


if __name__ == "__main__":
    sys.exit(main())
