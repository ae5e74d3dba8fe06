"""Snakemake script of rule `mesh`: one gmsh mesh and its JSON sidecar (paper §2.1, §2.4.1)."""
import logging

from ureterfsi.mesh import build_mesh

logging.basicConfig(filename=snakemake.log[0], level=logging.INFO,  # noqa: F821
                    format="%(asctime)s %(levelname)s %(message)s")
w = snakemake.wildcards  # noqa: F821
logging.info("mesh model %s, level %s, symmetry %s", w.model, w.level, w.symmetry)
try:
    info = build_mesh(snakemake.config, w.model, w.level, w.symmetry,  # noqa: F821
                      snakemake.output.msh, snakemake.output.json)  # noqa: F821
except Exception:
    logging.exception("mesh generation failed")
    raise
logging.info("%d cells %s, %d nodes, minSICN %.3f, %d hole channels, %.1f s", info["cells_total"], info["cells"],
             info["nodes"], info["quality_minSICN"]["min"], info["hole_channels_found"], info["mesh_wall_time_s"])
