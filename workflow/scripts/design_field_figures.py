"""Snakemake script of rules design_field_hole_flow and design_field_stent_wss: a field figure of one design point's
run (ureterfsi.plotting.fields.run_field_figure) at every snapshot of its field files, written atomically in every
configured format."""
import logging

from ureterfsi.designs.space import PARAMETERS
from ureterfsi.plotting.fields import run_field_figure
from ureterfsi.plotting.style import save_figure
from ureterfsi.data.checked import RUN_FILE, open_netcdf
from ureterfsi.workflow.log import run_script

smk = snakemake  # noqa: F821


def main():
    run = open_netcdf(smk.input.run, RUN_FILE)
    w = smk.wildcards
    values = ", ".join(f"{k} {v:g} {PARAMETERS[k].units}" for k, v in smk.params.point_values.items())
    what = (f"design study {w.design_study}, point {w.point}; model {run.attrs['model']}, {run.attrs['fidelity']}, "
            f"{run.attrs['symmetry']}, mesh {run.attrs['mesh_level']}\n{values}")
    kind = smk.rule.removeprefix("design_")
    fig = run_field_figure(kind, smk.input.run, smk.params.point_config, None, what)
    save_figure(fig, list(smk.output), dpi=float(smk.params.dpi))
    logging.info("%s -> %s", smk.rule, list(smk.output))


run_script(smk, main)
