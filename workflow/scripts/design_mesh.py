"""Snakemake script of rule `design_mesh`: the mesh of one or more design points (ureterfsi.designs)."""
import logging

from ureterfsi.designs import mesh_request
from ureterfsi.mesh import build_mesh

logging.basicConfig(filename=snakemake.log[0], level=logging.INFO,  # noqa: F821
                    format="%(asctime)s %(levelname)s %(message)s")
cfg, model, level, symmetry = mesh_request(snakemake.config, snakemake.wildcards.mesh_id)  # noqa: F821
try:
    info = build_mesh(cfg, model, level, symmetry, snakemake.output.msh, snakemake.output.json)  # noqa: F821
except Exception:
    logging.exception("mesh generation failed")
    raise
logging.info("design mesh %s: model %s, %s, %s: %d cells, %.1f s", snakemake.wildcards.mesh_id, model, level,  # noqa: F821
             symmetry, info["cells_total"], info["mesh_wall_time_s"])
