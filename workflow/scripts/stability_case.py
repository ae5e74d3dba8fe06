"""Snakemake script of rule `stability_case`: one case of the stability matrix -> results/stability/{case}.nc
(ureterfsi.stability.run_case; a failing case is a result with its diagnosis, not a failed job)."""
import logging

from ureterfsi.stability import case_by_name, run_case, write_case  # first: netCDF4 before dolfinx

logging.basicConfig(filename=snakemake.log[0], level=logging.INFO,  # noqa: F821
                    format="%(asctime)s %(name)s: %(message)s")
cfg = snakemake.config  # noqa: F821
case = case_by_name(cfg, snakemake.wildcards.case)  # noqa: F821
try:
    meshes = list(snakemake.input)  # noqa: F821  (none for a hole_elements case: it builds its own)
    ds = run_case(cfg, case, mesh_path=meshes[0] if meshes else None)
    write_case(ds, snakemake.output[0])  # noqa: F821
except Exception:
    logging.exception("stability case %s could not be recorded", case.name)
    raise
logging.info("case %s: %s in %.1f s%s", case.name, ds["outcome"].item(), ds["wall_time"].item(),
             f"; {ds['diagnosis'].item()}" if ds["diagnosis"].item() else "")
