"""Snakemake script of every figure rule (workflow/rules/figures.smk): the figure is chosen by the rule
name; the outputs are written atomically in every configured format (ureterfsi.plotting.paper)."""
import logging

from ureterfsi.analyses import aggregate
from ureterfsi.plotting import paper as plotting
from ureterfsi.plotting.style import save_figure
from ureterfsi.data.checked import MESH_SIDECAR, open_netcdf, read_json
from ureterfsi.workflow.log import run_script

smk = snakemake  # noqa: F821


def models():
    return open_netcdf(smk.input.models, aggregate.MODELS_DATASET)


def draw(rule: str):
    if rule == "fig02_domain":
        info = read_json(smk.input.json, MESH_SIDECAR)
        model = smk.config["models"][str(info["model"])]
        what = f"{model['label']} between hole pairs" if model["stent"] else model["label"]
        return plotting.fig02_domain(
            smk.input.msh, hole_z=max(info["hole_pair_z"]) if info["hole_pair_z"] else None,
            title=f"Model {info['model']} ({what}), {info['symmetry']} model, "
                  f"{format(info['cells_total'], ',').replace(',', ' ')} elements: mesh in the plane x = 0")
    if rule == "fig03_mesh_convergence":
        return plotting.fig03_mesh_convergence(open_netcdf(smk.input.conv, aggregate.CONVERGENCE_DATASET))
    if rule == "fig04_outlet_flow":
        return plotting.fig04_outlet_flow(models())
    if rule == "fig05_wall_displacement":
        return plotting.fig05_wall_displacement(models(), times=[float(t) for t in smk.params.times])
    if rule in ("fig06_hole_velocity", "fig07_hole_velocity", "fig08_hole_velocity", "fig09_hole_velocity"):
        return plotting.fig_hole_velocity(models(), float(smk.params.time))
    if rule == "fig10_stent_von_mises":
        return plotting.fig10_stent_von_mises(models())
    if rule == "fig11_hole_flux":
        return plotting.fig_hole_flux(models())
    raise ValueError(f"plot_figure.py does not know rule {rule!r}")


def main():
    if smk.rule == "table1":
        cfg = {"models": smk.params.models}
        rows = plotting.table1(cfg, list(smk.input.sidecars))
        plotting.write_table1(rows, smk.output.csv, smk.output.md)
    else:
        fig = draw(smk.rule)
        save_figure(fig, list(smk.output), dpi=float(smk.params.figures["dpi"]))
    logging.info("%s -> %s", smk.rule, list(smk.output))


run_script(smk, main)
