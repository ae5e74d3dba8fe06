"""Snakemake script of rules `design_figures`, `design_map`, `design_sensitivity` and `design_passage`
(ureterfsi.plotting.designs)."""
import logging

from ureterfsi.data.checked import open_netcdf
from ureterfsi.designs.results import DESIGN_DATASET
from ureterfsi.plotting.style import save_figure
from ureterfsi.plotting.designs import map_figure, parameters_figure, passage_figure, sensitivity_figure
from ureterfsi.workflow.log import run_script

smk = snakemake  # noqa: F821
DRAW = {"design_figures": parameters_figure, "design_map": map_figure, "design_sensitivity": sensitivity_figure,
        "design_passage": passage_figure}


def main():
    ds = open_netcdf(smk.input[0], DESIGN_DATASET)
    save_figure(DRAW[smk.rule](ds), list(smk.output), dpi=smk.params.dpi)
    logging.info("%s -> %s", smk.rule, list(smk.output))


run_script(smk, main)
