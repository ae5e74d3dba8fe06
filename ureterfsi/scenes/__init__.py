"""Scenes for the generic FSI engine (ureterfsi.fsi) other than the ureter: verification benchmarks."""
