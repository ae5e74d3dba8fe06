"""Snakemake script of rules `design_figures`, `design_map` and `design_sensitivity` (ureterfsi.plotting_designs)."""
import logging

from ureterfsi.checked_io import open_netcdf
from ureterfsi.design_results import DESIGN_DATASET
from ureterfsi.plotting import save_figure
from ureterfsi.plotting_designs import map_figure, parameters_figure, sensitivity_figure
from ureterfsi.workflow_log import run_script

smk = snakemake  # noqa: F821
DRAW = {"design_figures": parameters_figure, "design_map": map_figure, "design_sensitivity": sensitivity_figure}


def main():
    ds = open_netcdf(smk.input[0], DESIGN_DATASET)
    save_figure(DRAW[smk.rule](ds), list(smk.output), dpi=smk.params.dpi)
    logging.info("%s -> %s", smk.rule, list(smk.output))


run_script(smk, main)
