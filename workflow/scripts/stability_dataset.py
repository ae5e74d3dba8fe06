"""Snakemake script of rule `stability_dataset`: the per-case files -> results/datasets/stability.nc (dim
`case`, ureterfsi.stability.combine) and a Markdown table of the outcomes."""
import logging

from ureterfsi.stability import combine, outcome_table, write_case
from ureterfsi.data.provenance import atomic_path
from ureterfsi.workflow.log import run_script

smk = snakemake  # noqa: F821


def main():
    ds = combine(list(smk.input.cases), smk.config)
    write_case(ds, smk.output.nc)
    table = outcome_table(ds)
    with atomic_path(smk.output.md) as tmp:
        tmp.write_text(table + "\n")
    logging.info("%d cases -> %s\n%s", ds.sizes["case"], smk.output.nc, table)


run_script(smk, main)
