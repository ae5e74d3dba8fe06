"""Snakemake script of rule `stability_map`: the stability dataset -> results/figures/stability_map.{png,pdf}
(ureterfsi.plotting.stability_map)."""
import logging

from ureterfsi.plotting import save_figure, stability_map  # first: netCDF4 before anything else

import xarray as xr  # noqa: E402

logging.basicConfig(filename=snakemake.log[0], level=logging.INFO,  # noqa: F821
                    format="%(asctime)s %(levelname)s %(message)s")
try:
    with xr.open_dataset(snakemake.input[0]) as ds:  # noqa: F821
        fig = stability_map(ds.load())
    save_figure(fig, list(snakemake.output), dpi=snakemake.params.figures["dpi"])  # noqa: F821
except Exception:
    logging.exception("stability map failed")
    raise
logging.info("-> %s", list(snakemake.output))  # noqa: F821
