"""Snakemake script of rule `ladder` (workflow/rules/ladder.smk): rung runs -> ladder dataset, Markdown table,
speed-accuracy figure and the rungs' figure quantities over each other (ureterfsi.analyses.ladder,
ureterfsi.plotting.ladder), all written atomically."""
import logging

from ureterfsi.analyses.aggregate import write_dataset
from ureterfsi.analyses import ladder
from ureterfsi.plotting.style import save_figure
from ureterfsi.plotting.ladder import ladder_overlay, ladder_pareto
from ureterfsi.data.provenance import atomic_path
from ureterfsi.workflow.log import run_script

smk = snakemake  # noqa: F821


def main():
    paths = dict(zip(smk.params.rungs, smk.input.runs))
    runs = ladder.open_runs(paths)
    ds = ladder.ladder_dataset(paths, smk.config, runs)
    write_dataset(ds, smk.output.dataset)
    table = ladder.ladder_table(ds)
    with atomic_path(smk.output.md) as tmp:
        tmp.write_text(table)
    dpi = smk.params.figures["dpi"]
    save_figure(ladder_pareto(ds), smk.output.figures, dpi=dpi)
    save_figure(ladder_overlay(runs, ds.attrs["reference"]), smk.output.overlay, dpi=dpi)
    logging.info("\n%s", table)


run_script(smk, main)
