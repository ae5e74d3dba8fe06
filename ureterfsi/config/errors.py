"""The one error of the configuration layer, the formatting of the values its messages quote and the slack of its
floating-point comparisons (RTOL)."""
from __future__ import annotations

RTOL = 1e-9  # relative slack of the floating-point comparisons of exact design ratios (e.g. 0.5/0.125 = 4)


class ConfigError(ValueError):
    """An invalid configuration; ``str`` is one line naming the key and the violated constraint."""

    def __init__(self, key: str, constraint: str):
        self.key = key
        self.constraint = " ".join(str(constraint).split())  # one line, whatever went in
        super().__init__(f"config error: {key}: {self.constraint}")


def fmt(v) -> str:
    """A value as a message quotes it: floats in %g, lists in brackets, others by repr."""
    if isinstance(v, bool) or v is None:
        return repr(v)
    if isinstance(v, float):
        return f"{v:g}"
    if isinstance(v, (list, tuple)):
        return "[" + ", ".join(fmt(x) for x in v) + "]"
    return repr(v)


def dotted(parts) -> str:
    """The dotted key (`a.b[0].c`) of a path of keys and list indices."""
    out = ""
    for p in parts:
        out += f"[{p}]" if isinstance(p, int) else (f".{p}" if out else str(p))
    return out or "<root>"
