"""Snakemake script of rule `ladder` (workflow/rules/ladder.smk): rung runs -> ladder dataset, Markdown table
and speed-accuracy figure (ureterfsi.ladder, ureterfsi.plotting.ladder_pareto), the rungs' figure quantities over
each other (ureterfsi.plotting.ladder_overlay), all written atomically."""
import logging

from ureterfsi.aggregate import write_dataset  # first: imports netCDF4 before dolfinx
from ureterfsi import ladder, plotting
from ureterfsi.provenance import atomic_path
from ureterfsi.workflow_log import run_script

smk = snakemake  # noqa: F821


def main():
    paths = dict(zip(smk.params.rungs, smk.input.runs))
    ds = ladder.ladder_dataset(paths, smk.config)
    write_dataset(ds, smk.output.dataset)
    with atomic_path(smk.output.md) as tmp:
        tmp.write_text(ladder.ladder_table(ds))
    plotting.save_figure(plotting.ladder_pareto(ds), smk.output.figures, dpi=smk.params.figures["dpi"])
    runs = ladder.open_runs(paths)
    plotting.save_figure(plotting.ladder_overlay(runs, ds.attrs["reference"]), smk.output.overlay,
                         dpi=smk.params.figures["dpi"])
    logging.info("\n%s", ladder.ladder_table(ds))


run_script(smk, main)
