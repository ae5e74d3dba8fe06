"""Snakemake script of rule `aggregate_convergence`: the runs of the convergence model on every mesh level
-> the mesh-convergence dataset (paper §3.1, Fig. 3; ureterfsi.aggregate.combine_levels)."""
import logging

from ureterfsi.aggregate import combine_levels, write_dataset  # first: imports netCDF4 before dolfinx

logging.basicConfig(filename=snakemake.log[0], level=logging.INFO,  # noqa: F821
                    format="%(asctime)s %(levelname)s %(message)s")
try:
    ds = combine_levels(list(snakemake.input.runs), float(snakemake.params.time), snakemake.config)  # noqa: F821
    write_dataset(ds, snakemake.output[0])  # noqa: F821
except Exception:
    logging.exception("aggregation of the mesh-convergence runs failed")
    raise
for lv in ds["level"].values:
    d = ds.sel(level=lv)
    logging.info("%s: %d cells, %d dofs, max line difference to the finest %.4g Pa", lv, d["cells"], d["dofs"],
                 d["line_max_difference_to_finest"])
