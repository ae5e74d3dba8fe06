"""python -m ureterfsi.config check <config.yaml> [<overlay.yaml> ...] (ureterfsi.config.cli)."""
import sys

from ureterfsi.config.cli import main

sys.exit(main())
