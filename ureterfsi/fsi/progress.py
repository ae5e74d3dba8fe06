"""Progress of a time integration: step k of ~N, per cent of simulated time, ETA from the recent rate.

ETA = (t_end - t) * r, with r the wall seconds per simulated second over the last `window` steps
(sum of wall / sum of dt). The first step of a process (form compilation, first factorisation) is left
out of r; until a second step is done the ETA is unknown. N = k + ceil((t_end - t) / dt_next).
"""
from __future__ import annotations

import math
from collections import deque
from typing import Optional


class Progress:
    def __init__(self, t_start: float, t_end: float, wall_start: float, window: int = 10):
        if not t_end > t_start or window < 1:
            raise ValueError(f"progress: need t_end > t_start and window >= 1, got {t_start}, {t_end}, {window}")
        self.t_start, self.t_end, self.window = t_start, t_end, window
        self._wall = wall_start
        self._recent: deque = deque(maxlen=window)
        self._steps_seen = 0
        self.step, self.time, self.dt_next = 0, t_start, math.nan

    def update(self, step: int, time: float, dt: float, dt_next: float, wall: float) -> None:
        """A step of length dt ended at simulated `time` and wall clock `wall`; the next will try dt_next."""
        if self._steps_seen:
            self._recent.append((wall - self._wall, dt))
        self._steps_seen += 1
        self._wall, self.step, self.time, self.dt_next = wall, step, time, dt_next

    @property
    def fraction(self) -> float:
        return min(1.0, (self.time - self.t_start) / (self.t_end - self.t_start))

    @property
    def total_steps(self) -> int:
        left = max(0.0, self.t_end - self.time)
        return self.step + (math.ceil(left / self.dt_next - 1e-9) if left > 1e-12 * self.t_end else 0)

    @property
    def eta(self) -> Optional[float]:
        """Wall seconds to t_end, or None before a step past the first."""
        if not self._recent:
            return None
        rate = sum(w for w, _ in self._recent) / sum(d for _, d in self._recent)
        return max(0.0, self.t_end - self.time) * rate

    def describe(self) -> str:
        eta = self.eta
        return (f"step {self.step} of ~{self.total_steps} ({100 * self.fraction:.1f} %)  ETA "
                + ("unknown" if eta is None else format_seconds(eta)))


def format_seconds(sec: float) -> str:
    sec = int(round(sec))
    h, rem = divmod(sec, 3600)
    m, s = divmod(rem, 60)
    return f"{h:d}:{m:02d}:{s:02d}"
