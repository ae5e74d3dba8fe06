"""Snakemake script of rule `stability_dataset`: the per-case files -> results/datasets/stability.nc (dim
`case`, ureterfsi.stability.combine) and a Markdown table of the outcomes."""
import logging

from ureterfsi.provenance import atomic_path
from ureterfsi.stability import combine, outcome_table, write_case  # first: netCDF4 before dolfinx

logging.basicConfig(filename=snakemake.log[0], level=logging.INFO,  # noqa: F821
                    format="%(asctime)s %(levelname)s %(message)s")
try:
    ds = combine(list(snakemake.input.cases), snakemake.config)  # noqa: F821
    write_case(ds, snakemake.output.nc)  # noqa: F821
    table = outcome_table(ds)
    with atomic_path(snakemake.output.md) as tmp:  # noqa: F821
        tmp.write_text(table + "\n")
except Exception:
    logging.exception("combining the stability cases failed")
    raise
logging.info("%d cases -> %s\n%s", ds.sizes["case"], snakemake.output.nc, table)  # noqa: F821
