"""The body of every Snakemake script (workflow/scripts): logging into the rule's log, one-line errors.

run_script(snakemake, fn) sends the `ureterfsi` loggers and the root logger to snakemake.log[0], runs fn();
an expected error (BadFile, ConfigError, SolveFailure) is written as its one line to the log and to stderr
and the job exits 1; any other error writes its traceback into the log, one line to stderr, and exits 1.
"""
from __future__ import annotations

import logging
import sys

from ureterfsi.data.checked import BadFile
from ureterfsi.config import ConfigError


def _expected(err: BaseException) -> bool:
    kinds = [BadFile, ConfigError]
    integrator = sys.modules.get("ureterfsi.fsi.integrator")   # loaded whenever a SolveFailure can be raised
    if integrator is not None:
        kinds.append(integrator.SolveFailure)
    return isinstance(err, tuple(kinds))


def run_script(smk, fn) -> None:
    """Run fn() as the script of rule smk.rule with logging to smk.log[0] (see the module docstring)."""
    handler = logging.FileHandler(smk.log[0], mode="w")
    handler.setFormatter(logging.Formatter("%(asctime)s %(name)s %(levelname)s: %(message)s", "%H:%M:%S"))
    logging.basicConfig(level=logging.INFO, handlers=[handler], force=True)  # Snakemake may have set one up
    pkg = logging.getLogger("ureterfsi")
    pkg.handlers[:], pkg.propagate = [], True
    pkg.setLevel(logging.INFO)
    log = logging.getLogger(f"ureterfsi.rule.{smk.rule}")
    try:
        fn()
    except Exception as err:
        if _expected(err):
            log.error("%s", err)
            line = str(err)
        else:
            log.exception("%s failed", smk.rule)
            line = f"{type(err).__name__}: {' '.join(str(err).split())} (traceback in {smk.log[0]})"
        handler.flush()
        print(f"rule {smk.rule}: {line}", file=sys.stderr)
        raise SystemExit(1) from None
