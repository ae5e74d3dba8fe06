"""Snakemake script of rules `design_figures`, `design_map` and `design_sensitivity` (ureterfsi.plotting_designs)."""
import logging

import xarray as xr

from ureterfsi.plotting import save_figure
from ureterfsi.plotting_designs import map_figure, parameters_figure, sensitivity_figure

logging.basicConfig(filename=snakemake.log[0], level=logging.INFO)  # noqa: F821
ds = xr.load_dataset(snakemake.input[0], decode_times=False)  # noqa: F821
DRAW = {"design_figures": parameters_figure, "design_map": map_figure, "design_sensitivity": sensitivity_figure}
draw = DRAW[snakemake.rule]  # noqa: F821
save_figure(draw(ds), list(snakemake.output), dpi=snakemake.params.dpi)  # noqa: F821
logging.info("%s -> %s", snakemake.rule, list(snakemake.output))  # noqa: F821
