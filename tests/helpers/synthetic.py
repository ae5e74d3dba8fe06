"""Synthetic datasets with known analytic values, shared by the analyses, data and integrity tests: per-run
datasets with the exact structure of ureterfsi.study.probes.probes_dataset (outlet flux = A sin(t), ...), and a
mesh-convergence dataset with the layout of aggregate.combine_levels and exact power laws."""
from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import xarray as xr
from mpi4py import MPI

from ureterfsi.data import cf as metadata
from ureterfsi.data.provenance import FORMAT_VERSION
from ureterfsi.fsi.wall_shear import WallShearHistory
from ureterfsi.mesh.geometry import StentModel, UreterGeometry, hole_pair_positions
from ureterfsi.study.options import RunSpec
from ureterfsi.study.probes import N_HOLE, N_LINE, UreterProbes, probes_dataset
from ureterfsi.study.stent_surface import StentSurface

FLUX_AMPLITUDE = 1e-8         # m^3/s
VM_BASE = 5e3                 # Pa


class _SyntheticSurface(StentSurface):
    """Stand-in for StentSurface: one unit of unit area per region, a shear stress along z that reverses in the lumen."""

    def __init__(self, cfg, holes, times):
        self.names = ["outer", "lumen"] + [f"hole_{k}" for k in range(holes)]
        self.wss = SimpleNamespace(region=np.arange(len(self.names)))
        self.history = WallShearHistory(len(self.names))
        for ti in times:
            tau = np.zeros((len(self.names), 3))
            tau[:, 2] = 0.05 * (1 + np.arange(len(self.names)) / 4)
            tau[1, 2] = 0.05 * np.sin(2 * np.pi * ti / 3)
            self.history.add(ti, tau, np.ones(len(self.names)))
        sc = cfg["stent_surface"]
        self.threshold, self.active_fraction = sc["low_wss_threshold"], sc["active_hole_fraction"]


class _SyntheticProbes:
    """Stand-in for UreterProbes with analytic series/snapshots (same names, shapes, attributes)."""

    series_names = UreterProbes.series_names
    snapshot_names = UreterProbes.snapshot_names
    obstruction_z = UreterProbes.obstruction_z          # unobstructed: no flow past an obstruction recorded

    def __init__(self, cfg, model, symmetry, times, level_factor=1.0):
        g = UreterGeometry.from_config(cfg)
        sm = StentModel.from_config(cfg, model)
        self.has_stent = sm.stent and symmetry != "axisymmetric"
        self.z = np.linspace(0.0, g.length, N_LINE)
        k = int(model)
        t = np.asarray(times)
        zc = cfg["peristalsis"]["start_position"] + cfg["peristalsis"]["speed"] * t
        self.series = {"time": list(t),
                       "outlet_flux": list(FLUX_AMPLITUDE * np.sin(t) * (1 + 0.05 * k)),
                       "inlet_flux": list(FLUX_AMPLITUDE * np.cos(t)),
                       "outlet_mean_axial_velocity": list(1e-3 * np.sin(2 * np.pi * t / 3) * (1 + 0.05 * k)),
                       "fluid_volume": list(np.full_like(t, 3e-6)),
                       "fluid_volume_rate": list(FLUX_AMPLITUDE * (np.cos(t) - np.sin(t) * (1 + 0.05 * k))),
                       "outlet_mean_pressure": list(130.0 + 5.0 * np.sin(t)),
                       "inlet_mean_pressure": list(130.0 + 5.0 * np.cos(t)),
                       "max_wall_displacement": list(1e-3 * np.ones_like(t))}
        self.snapshot_times = [pt for pt in cfg["time"]["probe_times"] if pt <= t[-1] + 1e-9]
        wall = [1e-3 * np.exp(-0.5 * ((self.z - (cfg["peristalsis"]["speed"] * pt)) / 4.25e-3) ** 2)
                * (1 - 0.03 * k) for pt in self.snapshot_times]
        self.snapshots = {"wall_radial_displacement": [w.tolist() for w in wall]}
        if self.has_stent:
            self.hole_z = hole_pair_positions(g, sm)
            sides = [1.0] if symmetry == "quarter" else [1.0, -1.0]
            self.holes = [(zk, sd, 1) for zk in self.hole_z for sd in sides]
            self.hole_s = np.linspace(-g.hole_radius, g.hole_radius, N_HOLE)
            self.outlet_hole_z = float(self.hole_z.max())
            vm = VM_BASE * (1 + 0.2 * np.sin(2 * np.pi * t / 3)) * (1 + 0.1 * k)
            self.series["stent_max_von_mises"] = list(vm)
            for c in "xy":
                self.series[f"stent_max_von_mises_{c}"] = list(np.full_like(t, 1e-3))
            self.series["stent_max_von_mises_z"] = list(np.clip(zc, 0, g.length))
            self.series["hole_flux"] = [[1e-10 * np.sin(2 * np.pi * (ti - zk / 0.02) / 3) for zk, _, _ in self.holes]
                                        for ti in t]
            self.series["hole_gross_exchange"] = [[1.2 * abs(q) for q in row] for row in self.series["hole_flux"]]
            self.surface = _SyntheticSurface(cfg, len(self.holes), t)
            self.comm = MPI.COMM_WORLD
            wss = {name: 0.05 * (1 + 0.5 * np.sin(2 * np.pi * t / 3) + 0.1 * k) for name in self.surface.names}
            self.series["stent_outer_wss"] = list(wss["outer"])
            self.series["stent_lumen_wss"] = list(0.5 * wss["lumen"])
            self.series["hole_wall_wss"] = np.array([wss[n] for n in self.surface.names[2:]]).T.tolist()
            for end in ("outlet", "inlet"):
                self.series[f"{end}_lumen_flux"] = list(1e-2 * np.asarray(self.series[f"{end}_flux"]))
            a = g.hole_radius
            self.snapshots["stent_von_mises_line"] = [
                (VM_BASE * level_factor * (1 + 0.3 * np.exp(-0.5 * ((self.z - 0.02 * pt) / 5e-3) ** 2))).tolist()
                for pt in self.snapshot_times]
            self.snapshots["hole_velocity_y"] = [(1e-3 * k * (1 + pt) * (1 - (self.hole_s / a) ** 2)).tolist()
                                                 for pt in self.snapshot_times]


def synthetic_run(cfg, model, level="coarse", symmetry="quarter", end=3.0, dt=0.01, refine=None,
                  level_factor=1.0, cells=1000, wall_time=10.0) -> xr.Dataset:
    """A per-run dataset built by the study's own probes_dataset from analytic probe values.

    refine=(t0, t1): halved steps in [t0, t1] (an adaptive time grid)."""
    t = np.round(np.arange(dt, end + 0.5 * dt, dt), 9)
    if refine:
        extra = np.arange(refine[0] + dt / 2, refine[1], dt)
        t = np.unique(np.round(np.r_[t, extra], 9))
    obs = _SyntheticProbes(cfg, model, symmetry, t, level_factor)
    records = [SimpleNamespace(time=ti, dt=dt, newton_iterations=3, residual=1e-9, min_ale_jacobian=0.9,
                               wall_time=0.1) for ti in t]
    spec = RunSpec(str(model), level, symmetry, "mesh.msh")
    return probes_dataset(obs, records, cfg, spec, {"cells": cells, "dofs": 10 * cells, "processes": 1,
                                                    "wall_time_s": wall_time, "time_step_s": dt,
                                                    "end_time_s": end})


P_LINE, P_FLUX, P_VM = 2.0, 1.5, 1.2


def convergence_dataset(cells=(60000, 140000, 320000), levels=("coarse", "medium", "fine"), flux_sign=1.0):
    """A mesh-convergence dataset with the layout of aggregate.combine_levels and exact power laws in
    h = N^(-1/3): line(z) = f(z) (1 + 40 h^2), peak flux = 1e-8 (1 + 30 h^1.5), peak stress = 6e3 (1 - 5 h^1.2)."""
    cells = np.asarray(cells, dtype=float)
    h = cells ** (-1.0 / 3.0)
    z = np.linspace(0.0, 0.05, 201)
    f = 5e3 * (1 + 0.3 * np.exp(-0.5 * ((z - 0.03) / 5e-3) ** 2))
    ds = xr.Dataset(
        {"stent_von_mises_line": (("level", "z"), f[None, :] * (1 + 40.0 * h[:, None] ** P_LINE)),
         "cells": ("level", cells), "dofs": ("level", 10 * cells), "processes": ("level", np.ones(3)),
         "wall_time": ("level", [10.0, 20.0, 40.0]),
         "peak_outlet_flux": ("level", 1e-8 * (1 + flux_sign * 30.0 * h ** P_FLUX)),
         "peak_stent_max_von_mises": ("level", 6e3 * (1 - 5.0 * h ** P_VM))},
        coords={"level": ("level", np.array(levels, dtype=object)), "z": ("z", z)})
    for name in list(ds.variables):
        units, long_name = metadata.cf_meta(str(name))
        ds[name].attrs.update(units=units, long_name=long_name)
    ds.attrs.update(model="3", probe_time=1.5, levels=",".join(levels), config_hash="abc", git_commit="deadbeef",
                    created="2026-01-01T00:00:00+00:00", ureterfsi_format_version=FORMAT_VERSION, run_fine_cells=int(cells[-1]), Conventions="CF-1.8",
                    title="ureterfsi mesh convergence: model 3, t = 1.5 s")
    return ds, f, z
