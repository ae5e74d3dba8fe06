"""Snakemake script of rule `mesh`: one gmsh mesh and its JSON sidecar (paper §2.1, §2.4.1)."""
import logging

from ureterfsi.mesh.build import build_mesh
from ureterfsi.workflow.log import run_script

smk = snakemake  # noqa: F821


def main():
    w = smk.wildcards
    logging.info("mesh model %s, level %s, symmetry %s", w.model, w.level, w.symmetry)
    info = build_mesh(smk.config, w.model, w.level, w.symmetry, smk.output.msh, smk.output.json)
    logging.info("%d cells %s, %d nodes, minSICN %.3f, %d hole channels, %.1f s", info["cells_total"], info["cells"],
                 info["nodes"], info["quality_minSICN"]["min"], info["hole_channels_found"], info["mesh_wall_time_s"])


run_script(smk, main)
