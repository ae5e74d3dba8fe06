"""Snakemake script of rules `gci` (workflow/rules/aggregate.smk: mesh-convergence dataset -> GCI dataset) and
`table_gci` (workflow/rules/figures.smk: GCI dataset -> CSV and Markdown table), both via ureterfsi.analyses.gci
(Grid Convergence Index, Celik et al. 2008). Outputs are written atomically."""
import logging

from ureterfsi.analyses.aggregate import CONVERGENCE_DATASET, write_dataset
from ureterfsi.analyses import gci
from ureterfsi.data.checked import open_netcdf
from ureterfsi.workflow.log import run_script

smk = snakemake  # noqa: F821


def run_gci():
    conv = open_netcdf(smk.input.conv, CONVERGENCE_DATASET)
    measure, dim = gci.mesh_measure(smk.input.mesh) if "mesh" in smk.input.keys() else (None, 3)
    ds = gci.gci_dataset(conv, points_z=[float(z) for z in smk.params.points_z],
                         safety_factor=float(smk.params.safety_factor), measure=measure, dim=dim, cfg=smk.config)
    write_dataset(ds, smk.output[0])
    logging.info("levels fine/medium/coarse = %s, r21 = %.4g, r32 = %.4g", ds.attrs["gci_levels"],
                 float(ds["r21"]), float(ds["r32"]))
    for i, q in enumerate(ds["quantity"].values):
        d, ext = ds.isel(quantity=i), ds[f"extrapolated_value_{q}"]
        logging.info("%s: p = %.4g, phi_ext = %.6g %s, GCI_fine21 = %.4g %%, %s %s", q, d["apparent_order"],
                     ext, ext.attrs["units"], 100 * float(d["gci_fine21"]), d["diagnosis"].item(), d["note"].item())


def run_table():
    ds = open_netcdf(smk.input.gci, gci.GCI_DATASET)
    gci.write_gci_table(ds, smk.output.csv, smk.output.md)


def main():
    {"gci": run_gci, "table_gci": run_table}[smk.rule]()
    logging.info("%s -> %s", smk.rule, list(smk.output))


run_script(smk, main)
