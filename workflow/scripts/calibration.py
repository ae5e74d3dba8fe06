"""Snakemake script of rule `calibration`: design-rule check and calibration of the wall (paper §2.4.2)."""
import logging
import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

from ureterfsi.calibration import format_report, write_report  # noqa: E402

logging.basicConfig(filename=snakemake.log[0], level=logging.INFO,  # noqa: F821
                    format="%(asctime)s %(levelname)s %(message)s")
log = logging.getLogger("calibration")
cfg = dict(snakemake.params.sections)  # noqa: F821  (geometry, ureter, peristalsis, time only)
try:
    report = write_report(cfg, snakemake.output[0])  # noqa: F821
except Exception:
    log.exception("calibration study failed")
    raise
log.info("\n%s", format_report(report))
