"""`python -m ureterfsi.study`: the command line of a study run (ureterfsi.study.cli)."""
from .cli import main

raise SystemExit(main())
