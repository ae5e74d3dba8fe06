"""Snakemake script of rule `aggregate_convergence`: the runs of the convergence model on every mesh level
-> the mesh-convergence dataset (paper §3.1, Fig. 3; ureterfsi.analyses.aggregate.combine_levels)."""
import logging

from ureterfsi.analyses.aggregate import combine_levels, write_dataset
from ureterfsi.workflow.log import run_script

smk = snakemake  # noqa: F821


def main():
    ds = combine_levels(list(smk.input.runs), float(smk.params.time), smk.config)
    write_dataset(ds, smk.output[0])
    for lv in ds["level"].values:
        d = ds.sel(level=lv)
        logging.info("%s: %d cells, %d dofs, max line difference to the finest %.4g Pa", lv, d["cells"], d["dofs"],
                     d["line_max_difference_to_finest"])


run_script(smk, main)
