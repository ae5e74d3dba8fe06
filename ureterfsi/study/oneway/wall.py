"""Step 1 of the one-way rung: the ureter wall alone in r-z (ureterfsi.scenes.wall_rz.WallModel), its inner- and
outer-surface motion recorded at every step (WallHistory), from a solve or a wall-motion file."""
from __future__ import annotations

import logging
import time as _time
from dataclasses import dataclass

import numpy as np
import xarray as xr

from ureterfsi.mesh import tags
from ureterfsi.fsi import Observer, SolverOptions, TimeIntegrator, TimeSettings
from ureterfsi.data.checked import BadFile, Contract
from ureterfsi.config import wall_sections
from ureterfsi.data.cf import WALL_MOTION_VARIABLES, attach
from ureterfsi.data.provenance import config_hash, provenance_attrs
from ureterfsi.scenes.ends import wall_urine_pressure
from ureterfsi.scenes.wall_rz import WallModel

log = logging.getLogger("ureterfsi.study.oneway")


# what WallHistory.from_dataset reads in a wall-motion file (rule wall_motion, write_wall_motion)
WALL_MOTION = Contract("wall-motion file", attrs=("wall_config_hash",),
                       variables=("time", "z_inner", "z_outer", "inner_radial_displacement",
                                  "inner_axial_displacement", "inner_radial_velocity", "inner_axial_velocity",
                                  "outer_radial_displacement"), units=WALL_MOTION_VARIABLES)

@dataclass
class WallHistory:
    """Recorded motion of the ureter wall surfaces (r-z solve): arrays (time, z)."""
    time: np.ndarray
    z_inner: np.ndarray
    inner_ur: np.ndarray
    inner_uz: np.ndarray
    inner_vr: np.ndarray
    inner_vz: np.ndarray
    z_outer: np.ndarray
    outer_ur: np.ndarray
    wall_time: float = 0.0

    def _at(self, field, zs, z, t):
        """Linear interpolation in time between recorded steps and in z along the surface."""
        k = int(np.clip(np.searchsorted(self.time, t), 1, len(self.time) - 1))
        t0, t1 = self.time[k - 1], self.time[k]
        a = 0.0 if t1 == t0 else float(np.clip((t - t0) / (t1 - t0), 0.0, 1.0))
        row = (1.0 - a) * field[k - 1] + a * field[k]
        return np.interp(z, zs, row)

    def inner(self, z, t):
        """(u_r, u_z, v_r, v_z) of the inner wall at axial positions z and time t."""
        return self.inner_displacement(z, t) + tuple(self._at(f, self.z_inner, z, t)
                                                     for f in (self.inner_vr, self.inner_vz))

    def inner_displacement(self, z, t):
        """(u_r, u_z) of the inner wall at axial positions z and time t."""
        return tuple(self._at(f, self.z_inner, z, t) for f in (self.inner_ur, self.inner_uz))

    def outer_radial(self, z, t):
        return self._at(self.outer_ur, self.z_outer, z, t)

    def to_dataset(self, cfg: dict) -> xr.Dataset:
        """CF-annotated dataset of the recorded motion, with provenance and the hash of the configuration
        sections the wall solve reads (`wall_config_hash`, checked by from_dataset)."""
        ds = attach(xr.Dataset(      # rows are times; written time last (CF §2.4)
            {"inner_radial_displacement": (("z_inner", "time"), np.asarray(self.inner_ur).T),
             "inner_axial_displacement": (("z_inner", "time"), np.asarray(self.inner_uz).T),
             "inner_radial_velocity": (("z_inner", "time"), np.asarray(self.inner_vr).T),
             "inner_axial_velocity": (("z_inner", "time"), np.asarray(self.inner_vz).T),
             "outer_radial_displacement": (("z_outer", "time"), np.asarray(self.outer_ur).T)},
            coords={"time": ("time", self.time), "z_inner": ("z_inner", self.z_inner),
                    "z_outer": ("z_outer", self.z_outer)}), WALL_MOTION_VARIABLES)
        ds.attrs.update(provenance_attrs(cfg, model="wall", fidelity="one_way", wall_solve_time_s=round(self.wall_time, 2),
                                         wall_config_hash=config_hash(wall_sections(cfg))))
        ds.attrs["Conventions"] = "CF-1.8"
        ds.attrs["title"] = "ureterfsi one-way rung, step 1: the ureter wall alone (r-z), surface motion"
        return ds

    @classmethod
    def from_dataset(cls, ds: xr.Dataset, cfg: dict, end: float, dt: float) -> "WallHistory":
        """The recorded motion of a wall_motion dataset, refused unless it was computed from the same wall
        configuration with the same time step and reaches `end`. Shorter steps where the wall solve halved one
        (TimeIntegrator: a failed step retried with dt/2) are accepted as long as every step time k dt of the run
        is recorded: the run then reads the wall at its own times."""
        want = config_hash(wall_sections(cfg))
        source = ds.encoding.get("source", "wall motion")
        if ds.attrs.get("wall_config_hash") != want:
            raise BadFile(source, f"wall motion computed from another configuration "
                                  f"(wall_config_hash {ds.attrs.get('wall_config_hash')} != {want})")
        t = ds["time"].values
        steps = np.diff(t)
        tol = 1e-9 * max(dt, end)
        run_times = dt * np.arange(int(round(end / dt)) + 1)
        recorded = t.size >= 2 and steps.max() <= dt + tol and all(np.abs(t - tk).min() <= tol for tk in run_times)
        if not recorded or t[-1] < end - tol:
            raise BadFile(source, f"wall motion covers [0, {t[-1] if t.size else 0:g}] s in steps "
                                  f"{steps.min() if steps.size else 0:g}-{steps.max() if steps.size else 0:g} s; "
                                  f"this run needs [0, {end:g}] s in steps of {dt:g} s")
        field = lambda name: ds[name].transpose("time", ...).values   # noqa: E731  (written time last, CF §2.4)
        return cls(t, ds["z_inner"].values, field("inner_radial_displacement"),
                   field("inner_axial_displacement"), field("inner_radial_velocity"),
                   field("inner_axial_velocity"), ds["z_outer"].values, field("outer_radial_displacement"),
                   float(ds.attrs.get("wall_solve_time_s", 0.0)))



class _SurfaceRecorder(Observer):
    """Observer of the r-z wall solve: inner/outer surface displacement and velocity each step."""

    def __init__(self, model):
        pb = model.problem
        self.pb = pb
        self.U, self.umap = pb.sub("displacement").collapse()
        self.V, self.vmap = pb.sub("velocity").collapse()
        xu, xv = self.U.tabulate_dof_coordinates(), self.V.tabulate_dof_coordinates()

        def nodes(space, coords, facet_tag):
            idx = model.surface_dofs(space, facet_tag)
            return idx[np.argsort(coords[idx, 1])]

        self.iu, self.iv = nodes(self.U, xu, tags.FLUID_URETER), nodes(self.V, xv, tags.FLUID_URETER)
        self.ou = nodes(self.U, xu, tags.URETER_OUTER)
        self.z_inner, self.z_outer = xu[self.iu, 1], xu[self.ou, 1]
        assert np.allclose(self.z_inner, xv[self.iv, 1])
        self.rows = {k: [] for k in ("time", "iur", "iuz", "ivr", "ivz", "our")}

    def observe(self, problem, step):
        x = self.pb.x.x.array
        u = x[self.umap].reshape(-1, 2)
        v = x[self.vmap].reshape(-1, 2)
        r = self.rows
        r["time"].append(problem.time)
        r["iur"].append(u[self.iu, 0].copy())
        r["iuz"].append(u[self.iu, 1].copy())
        r["ivr"].append(v[self.iv, 0].copy())
        r["ivz"].append(v[self.iv, 1].copy())
        r["our"].append(u[self.ou, 0].copy())

    def state(self):
        return {}

    def load_state(self, state):
        pass


def wall_history(cfg: dict, end: float, dt: float, nr: int = 4) -> WallHistory:
    """Transient r-z wall-alone solve over [0, end] with step dt (from rest, load ramped), under the urine pressure the
    configured ends give (scenes.ends.wall_urine_pressure; from its steady state at t = 0, as the fully coupled
    run's)."""
    t0 = _time.perf_counter()
    urine = wall_urine_pressure(cfg)
    model = WallModel(cfg, nr=nr, travelling=True, urine_pressure=urine,
                      options=SolverOptions(newton_rtol=1e-10, newton_atol=1e-12, newton_max_iterations=25,
                                            reuse_jacobian=True, reuse_contraction=0.3,
                                            predictor=cfg["solver"]["predictor"]))
    if urine is not None:
        model.problem.solve_steady(0.0)
    rec = _SurfaceRecorder(model)
    TimeIntegrator(model.problem, TimeSettings(end=end, dt=dt, output_times=cfg["time"]["probe_times"],
                                               max_halvings=cfg["solver"]["max_step_halvings"]),
                   observers=[rec]).run()
    r = {k: np.asarray(v) for k, v in rec.rows.items()}
    hist = WallHistory(r["time"], rec.z_inner, r["iur"], r["iuz"], r["ivr"], r["ivz"], rec.z_outer, r["our"],
                       _time.perf_counter() - t0)
    log.info("wall (r-z, %d x %d cells, %d steps): max outer radial displacement %.4e m, %.1f s",
             model.nr, model.nz, len(hist.time) - 1, hist.outer_ur.max(), hist.wall_time)
    return hist


class RecordedWall:
    """Outer-wall radial displacement along the probe line from the recorded wall motion."""

    def __init__(self, history: WallHistory, z: np.ndarray):
        self.history, self.z = history, z

    def radial_displacement(self, time: float) -> np.ndarray:
        return self.history.outer_radial(self.z, time)
