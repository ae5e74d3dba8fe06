"""The names of the stability matrix's cases: plain data importing nothing of the package, so that the
configuration checks (ureterfsi.config.study_checks.check_stability) name cases as ureterfsi.stability.cases does."""
from __future__ import annotations

import re
from dataclasses import dataclass


@dataclass(frozen=True)
class Case:
    """One point of the matrix: `axis` (a key of AXES, or "baseline") set to `value` (SI units)."""
    axis: str
    value: float | str | None = None

    @property
    def name(self) -> str:
        if self.axis == "baseline":
            return "baseline"
        return f"{self.axis}_{format_value(self.value)}"


def format_value(value) -> str:
    """Short file-name-safe label of a value: 0.001, 1e5, 2e-4, medium."""
    if isinstance(value, str):
        return value
    text = f"{float(value):.3g}"
    return re.sub(r"e([+-])0*(\d)", lambda m: "e" + ("-" if m.group(1) == "-" else "") + m.group(2), text)
