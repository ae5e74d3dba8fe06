"""The check of the end conditions (config `ends`): posable as configured."""
from __future__ import annotations

from .errors import ConfigError, fmt


def check_ends(cfg):
    """The end conditions can be posed: a closed junction resists backflow at least as much as forward flow. (The
    one-way rung poses them too: its wall takes the urine pressure, and a run is refused where the urine's pressure on
    the wall leaves the assumed one: study.oneway.rung.WallPressureRefused.)"""
    b = cfg["ends"]["bladder"]
    if b["junction_backward_resistance"] < b["junction_forward_resistance"]:
        raise ConfigError("ends.bladder.junction_backward_resistance",
                          f"{fmt(b['junction_backward_resistance'])} Pa s/m^3 < junction_forward_resistance "
                          f"{fmt(b['junction_forward_resistance'])} Pa s/m^3: a one-way valve resists backflow more")
