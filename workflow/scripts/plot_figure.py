"""Snakemake script of every figure rule (workflow/rules/figures.smk): the figure is chosen by the rule
name; the outputs are written atomically in every configured format (ureterfsi.plotting)."""
import json
import logging

from ureterfsi import aggregate  # noqa: F401  (first: imports netCDF4 before anything loads dolfinx)
from ureterfsi import plotting

smk = snakemake  # noqa: F821
logging.basicConfig(filename=smk.log[0], level=logging.INFO, format="%(asctime)s %(levelname)s %(message)s")


def models():
    return aggregate.open_run(smk.input.models)


def draw(rule: str):
    if rule == "fig02_domain":
        info = json.loads(open(smk.input.json).read())
        model = smk.config["models"][str(info["model"])]
        what = f"{model['label']} between hole pairs" if model["stent"] else model["label"]
        return plotting.fig02_domain(
            smk.input.msh, hole_z=max(info["hole_pair_z"]) if info["hole_pair_z"] else None,
            title=f"Model {info['model']} ({what}), {info['symmetry']} model, "
                  f"{format(info['cells_total'], ',').replace(',', ' ')} elements: mesh in the plane x = 0")
    if rule == "fig03_mesh_convergence":
        return plotting.fig03_mesh_convergence(aggregate.open_run(smk.input.conv))
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


try:
    if smk.rule == "table1":
        cfg = {"models": smk.params.models}
        rows = plotting.table1(cfg, list(smk.input.sidecars))
        plotting.write_table(rows, smk.output.csv, smk.output.md)
    else:
        fig = draw(smk.rule)
        plotting.save_figure(fig, list(smk.output), dpi=float(smk.params.figures["dpi"]))
except Exception:
    logging.exception("%s failed", smk.rule)
    raise
logging.info("%s -> %s", smk.rule, list(smk.output))
