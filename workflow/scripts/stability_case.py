"""Snakemake script of rule `stability_case`: one case of the stability matrix -> results/stability/{case}.nc
(ureterfsi.stability.run_case; a failing case is a result with its diagnosis, not a failed job)."""
import logging

from ureterfsi.stability import case_by_name, run_case, write_case
from ureterfsi.workflow.log import run_script

smk = snakemake  # noqa: F821


def main():
    case = case_by_name(smk.config, smk.wildcards.case)
    meshes = list(smk.input)   # none for a hole_elements case: it builds its own
    ds = run_case(smk.config, case, mesh_path=meshes[0] if meshes else None)
    write_case(ds, smk.output[0])
    logging.info("case %s: %s in %.1f s%s", case.name, ds["outcome"].item(), ds["wall_time"].item(),
                 f"; {ds['diagnosis'].item()}" if ds["diagnosis"].item() else "")


run_script(smk, main)
