"""Snakemake script of the field-figure rules (workflow/rules/fields.smk): a figure of the study run's field files
(ureterfsi.plotting.fields.run_field_figure), chosen by the rule name, written atomically in every configured
format."""
import logging

from ureterfsi.plotting.fields import run_field_figure
from ureterfsi.plotting.style import save_figure
from ureterfsi.data.checked import RUN_FILE, open_netcdf
from ureterfsi.workflow.log import run_script

smk = snakemake  # noqa: F821


def main():
    run = open_netcdf(smk.input.run, RUN_FILE)
    model = smk.config["models"][str(run.attrs["model"])]
    what = (f"model {run.attrs['model']} ({model['label']} between hole pairs), {run.attrs['fidelity']}, "
            f"{run.attrs['symmetry']}, mesh {run.attrs['mesh_level']}")
    fig = run_field_figure(smk.rule, smk.input.run, smk.config, smk.params.times, what)
    save_figure(fig, list(smk.output), dpi=float(smk.params.figures["dpi"]))
    logging.info("%s -> %s", smk.rule, list(smk.output))


run_script(smk, main)
