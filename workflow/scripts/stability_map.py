"""Snakemake script of rule `stability_map`: the stability dataset -> results/figures/stability_map.{png,pdf}
(ureterfsi.plotting.stability.stability_map)."""
import logging

from ureterfsi.plotting.stability import stability_map
from ureterfsi.plotting.style import save_figure
from ureterfsi.data.checked import Contract, open_netcdf
from ureterfsi.workflow.log import run_script

smk = snakemake  # noqa: F821
STABILITY_DATASET = Contract("stability dataset", attrs=("cases",), variables=("case", "outcome"))


def main():
    save_figure(stability_map(open_netcdf(smk.input[0], STABILITY_DATASET)), list(smk.output),
                dpi=smk.params.figures["dpi"])
    logging.info("-> %s", list(smk.output))


run_script(smk, main)
