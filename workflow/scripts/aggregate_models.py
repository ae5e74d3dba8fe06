"""Snakemake script of rule `aggregate_models`: the runs of every stent model on one mesh level -> one
dataset with dim `model` (ureterfsi.aggregate.combine_models)."""
import logging

from ureterfsi.aggregate import combine_models, write_dataset  # first: imports netCDF4 before dolfinx

logging.basicConfig(filename=snakemake.log[0], level=logging.INFO,  # noqa: F821
                    format="%(asctime)s %(levelname)s %(message)s")
try:
    ds = combine_models(list(snakemake.input.runs), snakemake.config,  # noqa: F821
                        time_grid=snakemake.params.time_grid)  # noqa: F821
    write_dataset(ds, snakemake.output[0])  # noqa: F821
except Exception:
    logging.exception("aggregation of the model runs failed")
    raise
logging.info("models %s, %d times (%s), %d probe times -> %s", list(ds["model"].values), ds.sizes["time"],
             ds.attrs["time_grid"], ds.sizes["probe_time"], snakemake.output[0])  # noqa: F821
