"""The check of the end conditions (config `ends`): posable as configured, with the one-way rung too."""
from __future__ import annotations

from ureterfsi.config.end_pressures import one_way_refusal

from .errors import ConfigError, fmt


def check_ends(cfg):
    """The end conditions can be posed: a closed junction resists backflow at least as much as forward flow, and
    no study run of the one-way rung has end pressures its wall would ignore (scenes.ends.one_way_refusal)."""
    b = cfg["ends"]["bladder"]
    if b["junction_backward_resistance"] < b["junction_forward_resistance"]:
        raise ConfigError("ends.bladder.junction_backward_resistance",
                          f"{fmt(b['junction_backward_resistance'])} Pa s/m^3 < junction_forward_resistance "
                          f"{fmt(b['junction_forward_resistance'])} Pa s/m^3: a one-way valve resists backflow more")
    study = cfg.get("study")
    if study and any(over.get("fidelity", study["fidelity"]) == "one_way"
                     for m, over in ({m: {} for m in cfg["models"]} | study["runs"]).items()):
        why = one_way_refusal(cfg)
        if why:
            raise ConfigError("ends", f"a study run of fidelity one_way: {why}")
