"""dolfinx's form compiler at DEBUG level, out of the solve logs.

FFCx compiles each new form with cffi, whose distutils logs every build step and gcc command at INFO on
the root logger (ffcx calls logging.basicConfig()): 4-64 lines per solve log. A filter on the root logger
re-emits those records on the logger "distutils" at DEBUG (`logging.getLogger("distutils").setLevel(DEBUG)`
shows them again).
"""
from __future__ import annotations

import logging
from pathlib import Path


class _CompilerToDebug(logging.Filter):
    def filter(self, record: logging.LogRecord) -> bool:
        if record.levelno >= logging.WARNING or not {"distutils", "_distutils"} & set(Path(record.pathname).parts):
            return True
        logging.getLogger("distutils").debug(record.getMessage())
        return False


def demote_compiler_logs() -> None:
    """Install the filter on the root logger (once per process)."""
    root = logging.getLogger()
    if not any(isinstance(f, _CompilerToDebug) for f in root.filters):
        root.addFilter(_CompilerToDebug())
