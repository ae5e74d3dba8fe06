"""Time integration driver: step control with retries, progress log, checkpoints, observers.

A step whose Newton iteration fails (or gives a non-finite residual) is retried with dt/2, at most
`max_halvings` times; after a success the step grows back by 2x per step up to the nominal dt.
Steps are shortened to land exactly on every output time. An inverted ALE mesh stops the run.
Checkpoints (every `checkpoint_interval` steps, atomically written) hold the state, its history
and the observers' records; a re-run with the same checkpoint path resumes from the last one.
"""
from __future__ import annotations

import abc
import json
import logging
import os
import time as _time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Optional, Sequence

import numpy as np

from ..provenance import atomic_path
from .problem import MonolithicFSI, NewtonDivergence
from .progress import Progress

log = logging.getLogger("ureterfsi.fsi")


class SolveFailure(RuntimeError):
    """A step could not be completed even with the smallest allowed time step, or the mesh inverted."""


@dataclass
class TimeSettings:
    end: float
    dt: float
    output_times: Sequence[float] = ()
    max_halvings: int = 4
    checkpoint_interval: int = 0          # steps; 0 disables
    checkpoint_path: Optional[str] = None
    min_ale_jacobian: float = 0.0         # stop when the minimum ALE Jacobian falls to this value


class Observer(abc.ABC):
    """Records quantities of interest after every accepted step."""

    @abc.abstractmethod
    def observe(self, problem: MonolithicFSI, step: int) -> None:
        """Called after the initial state (step 0) and after every accepted step."""

    def state(self) -> dict:
        """JSON-serialisable records, stored in checkpoints."""
        return {}

    def load_state(self, state: dict) -> None:
        pass


@dataclass
class StepRecord:
    step: int
    time: float
    dt: float
    newton_iterations: int
    residual: float
    min_ale_jacobian: float
    wall_time: float


@dataclass
class TimeIntegrator:
    problem: MonolithicFSI
    settings: TimeSettings
    observers: list = field(default_factory=list)
    records: list = field(default_factory=list)

    def _checkpoint_file(self):
        p = Path(self.settings.checkpoint_path)
        comm = self.problem.comm
        return p.with_name(f"{p.stem}.rank{comm.rank}of{comm.size}.npz")

    def save_checkpoint(self, step, dt_next):
        if not self.settings.checkpoint_path:
            return
        pb = self.problem
        meta = {"step": step, "time": pb.time, "dt_prev": pb.dt_prev, "dt_prev2": pb.dt_prev2, "dt_next": dt_next,
                "observers": [o.state() for o in self.observers],
                "records": [r.__dict__ for r in self.records]}
        with atomic_path(self._checkpoint_file()) as tmp:
            with open(tmp, "wb") as fh:
                np.savez(fh, x=pb.x.x.array, x_n=pb.x_n.x.array, x_nm1=pb.x_nm1.x.array, x_nm2=pb._x_nm2,
                         cells=np.asarray(pb.mesh.topology.original_cell_index),
                         meta=np.array(json.dumps(meta)))
        log.info("checkpoint: step %d t=%.6g s -> %s", step, pb.time, self._checkpoint_file())
        # A resumed run starts without the cached LU factorisation; drop it here too, so that the
        # uninterrupted and the resumed run do the same arithmetic after the checkpoint.
        pb.invalidate_jacobian()

    def has_checkpoint(self) -> bool:
        return bool(self.settings.checkpoint_path) and self._checkpoint_file().exists()

    def load_checkpoint(self):
        """Restore the last checkpoint if one exists. Returns (step, dt_next) or None."""
        if not self.has_checkpoint():
            return None
        pb = self.problem
        data = np.load(self._checkpoint_file())
        if data["x"].shape != pb.x.x.array.shape:
            raise SolveFailure(f"checkpoint {self._checkpoint_file()} does not match this problem "
                               f"({data['x'].shape} vs {pb.x.x.array.shape} values): delete it to restart")
        # The arrays are in process-local numbering. In parallel the graph partitioner need not give
        # the same cells to the same rank in two runs (same sizes, different layout): loading would
        # scramble the state (NaN residuals or a silently wrong state). Refuse instead.
        if "cells" in data and not np.array_equal(data["cells"], np.asarray(pb.mesh.topology.original_cell_index)):
            raise SolveFailure(f"checkpoint {self._checkpoint_file()} was written with a different mesh "
                               f"partition (the partitioner is not reproducible between parallel runs); "
                               f"its process-local arrays cannot be restored: delete it to restart")
        pb.x.x.array[:], pb.x_n.x.array[:], pb.x_nm1.x.array[:] = data["x"], data["x_n"], data["x_nm1"]
        meta = json.loads(str(data["meta"]))
        pb.time, pb.dt_prev = meta["time"], meta["dt_prev"]
        if "x_nm2" in data:       # the quadratic predictor's third state (absent from older checkpoints)
            pb._x_nm2[:], pb.dt_prev2 = data["x_nm2"], meta["dt_prev2"]
        pb.t.value = pb.time
        for obs, st in zip(self.observers, meta["observers"]):
            obs.load_state(st)
        self.records = [StepRecord(**r) for r in meta["records"]]
        log.info("resumed from checkpoint: step %d t=%.6g s", meta["step"], pb.time)
        return meta["step"], meta["dt_next"]

    def remove_checkpoint(self):
        if self.settings.checkpoint_path and self._checkpoint_file().exists():
            os.remove(self._checkpoint_file())

    def run(self):
        """Integrate to settings.end. Returns the list of StepRecord."""
        s, pb = self.settings, self.problem
        eps = 1e-9 * s.dt
        resumed = self.load_checkpoint()
        step, dt = resumed if resumed else (0, s.dt)
        if not resumed:
            for obs in self.observers:
                obs.observe(pb, step)
        outputs = sorted(t for t in s.output_times if t > pb.time + eps)
        t_first = self.records[0].time - self.records[0].dt if self.records else pb.time
        progress = Progress(min(t_first, pb.time), s.end, _time.perf_counter()) if s.end > pb.time + eps else None
        while pb.time < s.end - eps:
            target = min([s.end] + [t for t in outputs if t > pb.time + eps])
            dt_try = min(dt, target - pb.time)
            krylov0 = getattr(pb, "counters", {}).get("krylov_iterations")
            for attempt in range(s.max_halvings + 1):  # noqa: B007 - attempt tells if dt was halved
                tic = _time.perf_counter()
                try:
                    its, history = pb.step(dt_try)
                    break
                except NewtonDivergence as err:
                    log.warning("step %d t=%.6g s dt=%.3g s failed (%s; residuals %s); retrying with dt/2",
                                step + 1, pb.time + dt_try, dt_try, err,
                                ", ".join(f"{r:.2e}" for r in err.history))
                    last = err
                    dt_try *= 0.5
            else:
                raise SolveFailure(
                    f"step {step + 1} from t={pb.time:.6g} s failed after {s.max_halvings} halvings "
                    f"(last dt={2 * dt_try:.3g} s): {last}; residual history "
                    f"{', '.join(f'{r:.3e}' for r in last.history)}")
            step += 1
            jmin = pb.min_ale_jacobian()
            wall = _time.perf_counter() - tic
            self.records.append(StepRecord(step, pb.time, dt_try, its, history[-1], jmin, wall))
            progress.update(step, pb.time, dt_try, dt_try if attempt else min(s.dt, 2.0 * dt), _time.perf_counter())
            krylov = getattr(pb, "counters", {}).get("krylov_iterations")
            log.info("%s  t=%.5f s  dt=%.3e s  newton=%2d%s  residual=%.3e (from %.3e)  "
                     "min J_ale=%.4f  %.2f s/step", progress.describe(), pb.time, dt_try, its,
                     "" if krylov is None else f"  krylov={krylov - krylov0:3d}", history[-1],
                     history[0], jmin, wall)
            if jmin <= s.min_ale_jacobian:
                raise SolveFailure(f"ALE mesh inverted at t={pb.time:.6g} s (step {step}): minimum "
                                   f"Jacobian {jmin:.3e} <= {s.min_ale_jacobian}; refine the mesh near "
                                   f"the moving interface, stiffen the mesh motion or reduce the load")
            for obs in self.observers:
                obs.observe(pb, step)
            dt = dt_try if attempt else min(s.dt, 2.0 * dt)   # after a halving, grow back 2x per step
            if s.checkpoint_interval and step % s.checkpoint_interval == 0:
                self.save_checkpoint(step, dt)
        return self.records
