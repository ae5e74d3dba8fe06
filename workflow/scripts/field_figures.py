"""Snakemake script of the field-figure rules (workflow/rules/fields.smk): figures drawn from a run's field
files (ureterfsi.plotting.fields), chosen by the rule name, written atomically in every configured format."""
import logging
import os
from pathlib import Path

import numpy as np

from ureterfsi.data import fieldfiles
from ureterfsi.plotting import fields as plotting_fields
from ureterfsi.plotting.style import save_figure
from ureterfsi.data.checked import RUN_FILE, open_netcdf
from ureterfsi.mesh.geometry import UreterGeometry
from ureterfsi.workflow.log import run_script

smk = snakemake  # noqa: F821


def draw(rule: str):
    run = open_netcdf(smk.input.run, RUN_FILE)
    # the field directory as a clean path (messages name its files): fields_path is relative to the run file
    fs = fieldfiles.urine_fields(Path(os.path.normpath(Path(smk.input.run).parent / run.attrs["fields_path"])))
    geom = UreterGeometry.from_config(smk.config)
    model = smk.config["models"][str(run.attrs["model"])]
    what = (f"model {run.attrs['model']} ({model['label']} between hole pairs), {run.attrs['fidelity']}, "
            f"{run.attrs['symmetry']}, mesh {run.attrs['mesh_level']}")
    times = [float(t) for t in smk.params.times]
    win = plotting_fields.field_window(run["hole_z"].values, geom)
    if rule == "field_hole_flow":
        z = np.linspace(win.lo, win.hi, max(120, int(round((win.hi - win.lo) / 5.0e-5)) + 1))
        sec = fieldfiles.hole_flow_section(fs, times, win.centre, geom, z=z)
        in_plane = [float(run["hole_z"].values[k]) for k in win.holes if int(run["hole_axis"].values[k]) == 1]
        return plotting_fields.fig_hole_flow(sec, in_plane, geom, f"Urine flow {win.label}\n{what}")
    if rule == "field_stent_wss":
        ws = fieldfiles.stent_wall_shear(fs, times, win.centre, geom, half_width=win.half_width)
        holes = [(plotting_fields.hole_angle(int(run["hole_axis"].values[k]), float(run["hole_side"].values[k])),
                  float(run["hole_z"].values[k])) for k in win.holes]
        return plotting_fields.fig_stent_wall_shear(ws, holes, geom, float(run["low_wss_threshold"]),
                                                    f"Wall shear stress on the stent {win.label}\n{what}")
    if rule == "field_pressure":
        lines = fieldfiles.pressure_lines(fs, times, geom)
        centres = [float(run["pulse_centre"].sel(time=t, method="nearest")) for t in times]
        return plotting_fields.fig_pressure_along(lines, times, float(smk.config["fluid"]["reference_pressure"]),
                                                  centres, f"Urine pressure along the segment\n{what}")
    raise ValueError(f"field_figures.py does not know rule {rule!r}")


def main():
    fig = draw(smk.rule)
    save_figure(fig, list(smk.output), dpi=float(smk.params.figures["dpi"]))
    logging.info("%s -> %s", smk.rule, list(smk.output))


run_script(smk, main)
