"""The one-way rung against the fully coupled model at every level of the mesh study (does the one-way
rung hold at the medium and fine meshes, not only at the coarse one where the ladder measures it?).

Reads the mesh study's runs of both rungs, as the workflow makes them (`results/runs/{fidelity}/{symmetry}/
model{model}_{level}.nc`, Fig. 3's model and span), from one results directory or two (the two rungs are made
under different configuration files, so usually in two checkouts), and prints per level the size and cost of each
run and the one-way rung's error per figure quantity (ureterfsi.analyses.ladder.relative_error: relative max norm over the
common time span and probe times), then the error of each coarser level of a rung against its finest level.

    python benchmarks/mesh_study_rungs.py --fully-coupled /work/main/results --one-way /work/ow/results
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from ureterfsi.data.checked import RUN_FILE, open_netcdf  # noqa: E402
from ureterfsi.analyses.ladder import QUANTITIES, relative_error  # noqa: E402

RUNGS = ("fully_coupled", "one_way")


def run_path(results: Path, fidelity: str, symmetry: str, model: str, level: str) -> Path:
    return results / "runs" / fidelity / symmetry / f"model{model}_{level}.nc"


def common_span(runs: dict) -> dict:
    """Every run cut to the shortest run's end (the coarse level goes on to 3 s for the other figures), so each
    level's error is over the same span."""
    end = min(float(ds["time"].values[-1]) for ds in runs.values()) + 1e-9
    return {k: ds.sel(time=ds["time"] <= end, probe_time=ds["probe_time"] <= end) for k, ds in runs.items()}


def error_table(title: str, pairs: dict, quantities: list[str]) -> list[str]:
    """Markdown rows of relative_error(ref, run) per quantity, one column per (ref, run) pair."""
    lines = ["", title, "", "| quantity | " + " | ".join(pairs) + " |", "|---|" + "---|" * len(pairs)]
    for q in quantities:
        lines.append(f"| {q} | " + " | ".join(f"{relative_error(ref, run, q):.2e}" for ref, run in pairs.values())
                     + " |")
    return lines


def tables(runs: dict, levels: list[str]) -> str:
    """Markdown: cost per run, the one-way error per level, and each rung's error against its finest level."""
    quantities = [q for q in QUANTITIES if all(q in ds for ds in runs.values())]
    lines = ["| rung | level | cells | unknowns | processes | steps | wall s | s/step |", "|---|---|---|---|---|---|---|---|"]
    for (rung, level), ds in runs.items():
        steps = ds.sizes["time"] - 1
        wall = float(ds.attrs["wall_time_s"])
        lines.append(f"| {rung} | {level} | {ds.attrs.get('cells', '-')} | {ds.attrs.get('dofs', '-')} | "
                     f"{ds.attrs.get('processes', '-')} | {steps} | {wall:.0f} | {wall / steps:.1f} |")
    runs = common_span(runs)
    lines += error_table("One-way error against the fully coupled run of the same level (common span):",
                         {lv: (runs["fully_coupled", lv], runs["one_way", lv]) for lv in levels}, quantities)
    finest = levels[-1]
    for rung in RUNGS:
        lines += error_table(f"{rung}: each level against its {finest} level:",
                             {lv: (runs[rung, finest], runs[rung, lv]) for lv in levels[:-1]}, quantities)
    return "\n".join(lines)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--fully-coupled", type=Path, required=True, help="results directory of the fully coupled runs")
    ap.add_argument("--one-way", type=Path, required=True, help="results directory of the one-way runs")
    ap.add_argument("--model", default="3")
    ap.add_argument("--symmetry", default="quarter")
    ap.add_argument("--levels", nargs="+", default=["coarse", "medium", "fine"], help="coarse to fine")
    args = ap.parse_args()
    roots = {"fully_coupled": args.fully_coupled, "one_way": args.one_way}
    runs = {(rung, lv): open_netcdf(run_path(roots[rung], rung, args.symmetry, args.model, lv), RUN_FILE)
            for rung in RUNGS for lv in args.levels}
    print(tables(runs, args.levels))


if __name__ == "__main__":
    main()
