"""Command line: python -m ureterfsi.config check <config.yaml> [<overlay.yaml> ...]."""
from __future__ import annotations

import sys

from ureterfsi.data.provenance import config_hash

from .errors import ConfigError
from .validation import load_config_files


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    if len(argv) < 2 or argv[0] != "check":
        sys.stderr.write("usage: python -m ureterfsi.config check <config.yaml> [<overlay.yaml> ...]\n")
        return 2
    try:
        cfg = load_config_files(argv[1:])
    except ConfigError as err:
        sys.stderr.write(f"{err}\n")
        return 2
    print(f"config ok: {config_hash(cfg)}")
    return 0
