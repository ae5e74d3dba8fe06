"""Plausible magnitudes: every number of the configuration within its range (ureterfsi.config.ranges)."""
from __future__ import annotations

from ureterfsi.config.ranges import Range, range_of, unit_slip

from .errors import ConfigError, dotted, fmt


def _leaves(node, path=()):
    """(dotted key, value) of every number in the configuration, in its order."""
    if isinstance(node, dict):
        for k, v in node.items():
            yield from _leaves(v, path + (k,))
    elif isinstance(node, list):
        for i, v in enumerate(node):
            yield from _leaves(v, path + (i,))
    elif isinstance(node, (int, float)) and not isinstance(node, bool):
        yield dotted(path), node


def implausible(value: float, rng: Range) -> str:
    """Why `value` is outside `rng`, with the unit slip it most likely is."""
    units = "" if rng.units == "1" else f" {rng.units}"
    slip = unit_slip(value, rng)
    return (f"{fmt(float(value))}{units} is outside the plausible range [{rng.low:g}, {rng.high:g}]{units} "
            f"({rng.reason}){'; ' + slip if slip else ''}")


def check_plausible(cfg):
    """Every magnitude within its plausible range (ureterfsi.config.ranges.RANGES)."""
    for key, value in _leaves(cfg):
        rng = range_of(key)
        if rng is not None and not rng.low <= value <= rng.high:
            raise ConfigError(key, implausible(value, rng))
