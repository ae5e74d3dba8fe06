"""MonolithicFSI's time history: the variable-step BDF2 coefficients and the history they weigh (set_bdf), the BDF
time derivative, the predictor of a step's initial guess, and the state a restart needs (state, set_state)."""
from __future__ import annotations

import numpy as np


class HistoryMethods:
    """MonolithicFSI's methods over its states x, x_n, x_nm1, x_nm2 and their times (mixed into MonolithicFSI)."""

    def set_bdf(self, dt):
        """Variable-step BDF2 coefficients (Backward Euler when there is no previous step)."""
        if self.dt_prev is None:
            c = (1.0, -1.0, 0.0)
        else:
            w = dt / self.dt_prev
            c = ((1.0 + 2.0 * w) / (1.0 + w), -(1.0 + w), w * w / (1.0 + w))
        for const, val in zip(self.bdf, c):
            const.value = val
        self.dt.value = dt
        self._sync_history()

    def _sync_history(self) -> None:
        """history = b1 x_n + b2 x_nm1 (ghosts included), after each change of the BDF coefficients or x_n, x_nm1."""
        b1, b2 = float(self.bdf[1].value), float(self.bdf[2].value)
        np.multiply(b1, self.x_n.x.array, out=self.history.x.array)
        self.history.x.array[:] += b2 * self.x_nm1.x.array


    def time_derivative(self, dofs=slice(None)) -> np.ndarray:
        """The BDF time derivative (b0 x + b1 x_n + b2 x_nm1) / dt of the current state at the local `dofs`."""
        b0, b1, b2 = (float(c.value) for c in self.bdf)
        return (b0 * self.x.x.array[dofs] + b1 * self.x_n.x.array[dofs] + b2 * self.x_nm1.x.array[dofs]) \
            / float(self.dt.value)

    def _predict(self, guess: str, dt: float):
        """Newton's initial guess for the step to t_n + dt, into x."""
        self.x.x.array[:] = self.x_n.x.array
        if guess == "quadratic" and self.dt_prev and self.dt_prev2:
            # the parabola through (t_n-2, x_n-2), (t_n-1, x_n-1), (t_n, x_n) at t_n + dt: an O(dt^3) guess
            h1, h2 = self.dt_prev, self.dt_prev + self.dt_prev2      # t_n - t_n-1, t_n - t_n-2
            l1 = -dt * (dt + h2) / (h1 * (h2 - h1))
            l2 = dt * (dt + h1) / (h2 * (h2 - h1))
            self.x.x.array[:] += l1 * (self.x_nm1.x.array - self.x_n.x.array) + l2 * (self._x_nm2 - self.x_n.x.array)
        elif guess != "constant" and self.dt_prev:
            # x_n + (dt/dt_prev)(x_n - x_n-1): first-order extrapolation, an O(dt^2) guess instead of O(dt)
            self.x.x.array[:] += (dt / self.dt_prev) * (self.x_n.x.array - self.x_nm1.x.array)


    def state(self) -> dict:
        """What a restart needs: copies of the process-local arrays x, x_n, x_nm1 and x_nm2 (the BDF
        history of the last accepted step), the times time, dt_prev, dt_prev2 and the lumped end conditions'
        pressures (end_conditions)."""
        return {"x": self.x.x.array.copy(), "x_n": self.x_n.x.array.copy(), "x_nm1": self.x_nm1.x.array.copy(),
                "x_nm2": self._x_nm2.copy(), "time": self.time, "dt_prev": self.dt_prev, "dt_prev2": self.dt_prev2,
                "end_conditions": self.end_conditions.state()}

    def set_state(self, state: dict) -> None:
        """Restore a `state()` (arrays of this problem's size): the arrays, the times and the load time t."""
        for key, array in (("x", self.x.x.array), ("x_n", self.x_n.x.array), ("x_nm1", self.x_nm1.x.array),
                           ("x_nm2", self._x_nm2)):
            array[:] = state[key]
        self._sync_history()
        self.time, self.dt_prev, self.dt_prev2 = state["time"], state["dt_prev"], state["dt_prev2"]
        if "end_conditions" in state:
            self.end_conditions.set_state(state["end_conditions"])
        self.t.value = self.time
        self._reaction_ready = False    # the kept residual is not of the restored state
