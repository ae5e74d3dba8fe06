"""Time integration driver: step control with retries, progress log, checkpoints, observers.

A step whose Newton iteration fails (or gives a non-finite residual) is retried with dt/2, at most
`max_halvings` times; after a success the step grows back by 2x per step up to the nominal dt.
Steps are shortened to land exactly on every output time. An inverted ALE mesh stops the run.
Checkpoints (every `checkpoint_interval` steps and at the end, atomically written) hold the state, its
history, the observers' records and the run's identity (TimeSettings.identity); a re-run with the same
checkpoint path resumes from the last one only if it is readable, complete, of this problem's size
and partition and of the same identity, and not past the run's end. Otherwise it is set aside (renamed *.stale-<UTC time>.npz),
one line says why, and the run starts from t = 0.
"""
from __future__ import annotations

import abc
import hashlib
import json
import logging
import os
import time as _time
from dataclasses import dataclass, field
from datetime import datetime, timezone
from pathlib import Path
from typing import Mapping, Optional, Sequence

import numpy as np

from ureterfsi.data.provenance import atomic_path
from .newton import NewtonDivergence
from .problem import MonolithicFSI
from .progress import Progress

log = logging.getLogger("ureterfsi.fsi")


class SolveFailure(RuntimeError):
    """The run cannot go on: a step failed at the smallest allowed time step, or the mesh inverted."""


class StepFailure(SolveFailure):
    """A step failed even after max_halvings halvings; `cause` is the NewtonDivergence of its last attempt."""

    def __init__(self, message, cause: NewtonDivergence):
        super().__init__(message)
        self.cause = cause


class MeshInversion(SolveFailure):
    """The minimum ALE Jacobian `min_jacobian` fell to the limit at `time` (the state of the last step)."""

    def __init__(self, message, time: float, min_jacobian: float):
        super().__init__(message)
        self.time, self.min_jacobian = time, min_jacobian


@dataclass
class TimeSettings:
    end: float
    dt: float
    output_times: Sequence[float] = ()
    max_halvings: int = 4
    checkpoint_interval: int = 0          # steps; 0 disables
    checkpoint_path: Optional[str] = None
    min_ale_jacobian: float = 0.0         # stop when the minimum ALE Jacobian falls to this value
    # what determines the run, component name -> value (strings; the caller's choice, e.g. config keys,
    # file hashes, versions): a checkpoint of another identity is set aside, never resumed
    identity: Mapping[str, str] = field(default_factory=dict)


STATE_ARRAYS = ("x", "x_n", "x_nm1", "x_nm2")    # the arrays of MonolithicFSI.state()
_CHECKPOINT_ARRAYS = STATE_ARRAYS + ("cells", "meta")
_CHECKPOINT_META = ("step", "time", "dt_prev", "dt_prev2", "dt_next", "observers", "records", "identity",
                    "identity_hash")


def identity_hash(identity: Mapping[str, str]) -> str:
    """SHA-256 (hex) of the canonical JSON form of a run identity."""
    return hashlib.sha256(json.dumps(dict(identity), sort_keys=True).encode()).hexdigest()


def identity_differences(stored: Mapping[str, str], wanted: Mapping[str, str], limit: int = 4) -> str:
    """'key old -> new; ...' for the components that differ (at most `limit`, then how many more)."""
    def short(v):
        v = "(absent)" if v is None else str(v)
        return v[:12] + "..." if len(v) > 24 else v

    keys = sorted(k for k in set(stored) | set(wanted) if stored.get(k) != wanted.get(k))
    text = "; ".join(f"{k} {short(stored.get(k))} -> {short(wanted.get(k))}" for k in keys[:limit])
    return text + (f"; and {len(keys) - limit} more" if len(keys) > limit else "")


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

    def cannot_resume(self, state: dict) -> str:
        """Why a checkpoint holding `state` (from state()) cannot be resumed by this observer, '' if it can
        (e.g. files it wrote before the checkpoint are gone)."""
        return ""


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
class FailedAttempt:
    """A step attempt Newton could not complete: retried with dt/2 (`halved`), or the last attempt of a
    step the run gives up on; `time` is the end of the attempt."""
    step: int
    time: float
    dt: float
    halved: bool


@dataclass
class TimeIntegrator:
    problem: MonolithicFSI
    settings: TimeSettings
    observers: list = field(default_factory=list)
    records: list = field(default_factory=list)
    failed_attempts: list = field(default_factory=list)
    resumed_from: int = 0      # the step of the checkpoint run() went on from (0: from the initial state)
    _pending: Optional[tuple] = field(default=None, init=False, repr=False)   # checked, not yet restored

    def _checkpoint_file(self):
        p = Path(self.settings.checkpoint_path)
        comm = self.problem.comm
        return p.with_name(f"{p.stem}.rank{comm.rank}of{comm.size}.npz")

    def save_checkpoint(self, step, dt_next):
        if not self.settings.checkpoint_path:
            return
        pb = self.problem
        state = pb.state()
        identity = {str(k): str(v) for k, v in self.settings.identity.items()}
        meta = {"step": step, "time": state["time"], "dt_prev": state["dt_prev"], "dt_prev2": state["dt_prev2"],
                "dt_next": dt_next,
                "end_conditions": state["end_conditions"], "observers": [o.state() for o in self.observers],
                "records": [r.__dict__ for r in self.records],
                "failed_attempts": [a.__dict__ for a in self.failed_attempts],
                "identity": identity, "identity_hash": identity_hash(identity)}
        with atomic_path(self._checkpoint_file()) as tmp:
            with open(tmp, "wb") as fh:
                np.savez(fh, **{k: state[k] for k in STATE_ARRAYS},
                         cells=np.asarray(pb.mesh.topology.original_cell_index),
                         meta=np.array(json.dumps(meta)))
        log.info("checkpoint: step %d t=%.6g s -> %s", step, pb.time, self._checkpoint_file())
        # A resumed run starts without the cached LU factorisation; drop it here too, so that the
        # uninterrupted and the resumed run do the same arithmetic after the checkpoint.
        pb.invalidate_jacobian()

    def has_checkpoint(self) -> bool:
        """A checkpoint this run can resume from exists (collective). A stale or unreadable one is set
        aside (renamed, one log line) and the answer is False."""
        return self._resumable() is not None

    def _read_checkpoint(self, path: Path):
        """(arrays, meta) of this rank's checkpoint, or (None, why it cannot be resumed)."""
        pb = self.problem
        if not path.exists():
            return None, "missing on this rank"
        try:
            with np.load(path) as npz:
                missing = [k for k in _CHECKPOINT_ARRAYS if k not in npz.files]
                if missing:
                    return None, f"incomplete (no array {missing[0]!r})"
                data = {k: npz[k] for k in _CHECKPOINT_ARRAYS}
            meta = json.loads(str(data["meta"]))
        except Exception as err:  # BadZipFile, EOFError, zlib.error, ValueError (json), OSError
            return None, f"unreadable ({type(err).__name__}: {' '.join(str(err).split())})"
        missing = [k for k in _CHECKPOINT_META if k not in meta]
        if missing:
            return None, f"incomplete (no {missing[0]!r} in its metadata)"
        if meta["time"] > self.settings.end + 1e-9 * self.settings.dt:
            return None, f"past this run's end (its t = {meta['time']:.6g} s, the end {self.settings.end:.6g} s)"
        wanted = {str(k): str(v) for k, v in self.settings.identity.items()}
        if meta["identity_hash"] != identity_hash(wanted) or meta["identity"] != wanted:
            return None, f"written by another run ({identity_differences(meta['identity'], wanted)})"
        n = pb.x.x.array.shape
        for key in STATE_ARRAYS:
            if data[key].shape != n:
                return None, f"of another problem size ({key} has {data[key].shape[0]} values, this problem {n[0]})"
        # The arrays are in process-local numbering. In parallel the graph partitioner need not give
        # the same cells to the same rank in two runs (same sizes, different layout): restoring would
        # scramble the state.
        if not np.array_equal(data["cells"], np.asarray(pb.mesh.topology.original_cell_index)):
            return None, "written with another mesh partition (its process-local arrays cannot be restored)"
        if len(meta["observers"]) != len(self.observers):
            return None, f"holds {len(meta['observers'])} observer records, this run has {len(self.observers)} observers"
        for obs, st in zip(self.observers, meta["observers"]):
            why = obs.cannot_resume(st)
            if why:
                return None, why
        return (data, meta), None

    def _resumable(self):
        """(arrays, meta) of a checkpoint every rank can resume from, or None (collective); a checkpoint
        that cannot be resumed is set aside."""
        if not self.settings.checkpoint_path:
            return None
        if self._pending is not None:
            return self._pending
        path, comm = self._checkpoint_file(), self.problem.comm
        if not comm.allreduce(int(path.exists())):
            return None
        state, why = self._read_checkpoint(path)
        whys = comm.allgather(why)
        bad = [(r, w) for r, w in enumerate(whys) if w]
        if not bad:
            self._pending = state
            return state
        stale = None
        if path.exists():
            stamp = datetime.now(timezone.utc).strftime("%Y%m%dT%H%M%SZ")
            stale = path.with_name(f"{path.stem}.stale-{stamp}.npz")
            k = 1
            while stale.exists():
                stale, k = path.with_name(f"{path.stem}.stale-{stamp}-{k}.npz"), k + 1
            os.replace(path, stale)
        comm.Barrier()
        rank, why = bad[0]
        where = f"rank {rank}: " if comm.size > 1 else ""
        if comm.rank == 0:
            log.warning("checkpoint %s not resumed, %s%s; set aside as %s; starting from t = 0", path, where, why,
                        stale.name if stale else "(none on this rank)")
        return None

    def load_checkpoint(self):
        """Restore the last checkpoint if this run can resume from it (see has_checkpoint). Returns
        (step, dt_next) or None."""
        state = self._resumable()
        if state is None:
            return None
        self._pending = None
        data, meta = state
        pb = self.problem
        pb.set_state({k: data[k] for k in STATE_ARRAYS}
                     | {k: meta[k] for k in ("time", "dt_prev", "dt_prev2", "end_conditions") if k in meta})
        for obs, st in zip(self.observers, meta["observers"]):
            obs.load_state(st)
        self.records = [StepRecord(**r) for r in meta["records"]]
        self.failed_attempts = [FailedAttempt(**a) for a in meta.get("failed_attempts", [])]
        log.info("resumed from checkpoint: step %d t=%.6g s", meta["step"], pb.time)
        self.resumed_from = meta["step"]
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
                    self.failed_attempts.append(FailedAttempt(step + 1, pb.time + dt_try, dt_try,
                                                              attempt < s.max_halvings))
                    dt_try *= 0.5
            else:
                raise StepFailure(
                    f"step {step + 1} from t={pb.time:.6g} s failed after {s.max_halvings} halvings "
                    f"(last dt={2 * dt_try:.3g} s): {last}; residual history "
                    f"{', '.join(f'{r:.3e}' for r in last.history)}", last)
            step += 1
            jmin = pb.min_ale_jacobian()
            wall = _time.perf_counter() - tic
            self.records.append(StepRecord(step, pb.time, dt_try, its, history[-1], jmin, wall))
            progress.update(step, pb.time, dt_try, dt_try if attempt else min(s.dt, 2.0 * dt), _time.perf_counter())
            counters = getattr(pb, "counters", {})
            # Krylov iterations of Newton's linear solves (none under the partitioned sweeps, which use LU per block)
            krylov = None if "sweeps" in counters else counters.get("krylov_iterations")
            log.info("%s  t=%.5f s  dt=%.3e s  %s=%2d%s  residual=%.3e (from %.3e)  "
                     "min J_ale=%.4f  %.2f s/step", progress.describe(), pb.time, dt_try,
                     "sweeps" if "sweeps" in counters else "newton", its,
                     "" if krylov is None else f"  krylov={krylov - krylov0:3d}", history[-1],
                     history[0], jmin, wall)
            if jmin <= s.min_ale_jacobian:
                _, where = pb.min_ale_jacobian_at()
                raise MeshInversion(f"ALE mesh inverted at t={pb.time:.6g} s (step {step}): minimum "
                                    f"Jacobian {jmin:.3e} <= {s.min_ale_jacobian} at the reference point "
                                    f"({', '.join(f'{c:.4g}' for c in where)}) m; refine the mesh near "
                                    f"the moving interface, stiffen the mesh motion or reduce the load",
                                    pb.time, jmin)
            for obs in self.observers:
                obs.observe(pb, step)
            dt = dt_try if attempt else min(s.dt, 2.0 * dt)   # after a halving, grow back 2x per step
            if s.checkpoint_interval and step % s.checkpoint_interval == 0:
                self.save_checkpoint(step, dt)
        if s.checkpoint_interval and step % s.checkpoint_interval and step > self.resumed_from:
            self.save_checkpoint(step, dt)    # the end state too: a longer run of the same identity goes on from it
        return self.records
