"""The limits that end a stability case (docs/stability.md): "none" for a stable case."""
from __future__ import annotations

import math

LIMITS = ("none", "newton", "nan", "ale_inversion", "energy", "volume", "wall_time", "exception")


class StabilityLimit(RuntimeError):
    """A case reached the limit `limit` (one of LIMITS) at `time`, at the reference (r, z) `where`."""

    def __init__(self, limit: str, message: str, time: float = math.nan, where=(math.nan, math.nan),
                 what: str = "", value: float = math.nan):
        super().__init__(message)
        self.limit, self.time, self.where, self.what, self.value = limit, time, tuple(where), what, value
