"""Snakemake script of rule `design_mesh`: the mesh of one or more design points (ureterfsi.designs.space)."""
import logging

from ureterfsi.designs.expand import mesh_request
from ureterfsi.mesh.build import build_mesh
from ureterfsi.workflow.log import run_script

smk = snakemake  # noqa: F821


def main():
    cfg, model, level, symmetry = mesh_request(smk.config, smk.wildcards.mesh_id)
    info = build_mesh(cfg, model, level, symmetry, smk.output.msh, smk.output.json)
    logging.info("design mesh %s: model %s, %s, %s: %d cells, %.1f s", smk.wildcards.mesh_id, model, level,
                 symmetry, info["cells_total"], info["mesh_wall_time_s"])


run_script(smk, main)
