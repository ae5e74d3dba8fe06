"""The one-way rung as a run: the wall-motion job, the scene posed from the three steps, its run and diagnostics."""
from __future__ import annotations

import logging
from functools import partial

import numpy as np
import xarray as xr
from dolfinx import fem
from mpi4py import MPI

from ureterfsi.config import one_way_unposable
from ureterfsi.config.end_pressures import wall_pressure, wall_pressure_posed
from ureterfsi.mesh import tags
from ureterfsi.study.fields import oneway_parts
from ureterfsi.fsi import Observer, SolveFailure, TimeSettings
from ureterfsi.fsi.problem import MonolithicFSI
from ureterfsi.fsi.submesh import extract
from ureterfsi.mesh.geometry import StentModel, UreterGeometry
from ureterfsi.data.checked import open_netcdf
from ureterfsi.data.cf import write_netcdf
from ureterfsi.scenes.ureter import materials
from ureterfsi.study import pipeline
from ureterfsi.study.options import RunSpec
from ureterfsi.study.probes import N_LINE, UreterProbes
from ureterfsi.study.oneway.wall import RecordedWall, WALL_MOTION, WallHistory, wall_history
from ureterfsi.study.oneway.urine import fluid_problem
from ureterfsi.study.oneway.stent import QuasiStaticStent

log = logging.getLogger("ureterfsi.study.oneway")


def write_wall_motion(cfg: dict, out_path: str) -> xr.Dataset:
    """Step 1 of the rung as a job of its own: the wall over [0, time.end] in steps of time.dt, written
    atomically. Every one-way run of the study reads it (their wall is the same: geometry and load do not
    depend on the stent model or the 3D mesh)."""
    if one_way_unposable(cfg):
        raise SystemExit(one_way_unposable(cfg))
    ds = wall_history(cfg, cfg["time"]["end"], cfg["time"]["dt"]).to_dataset(cfg)
    write_netcdf(ds, out_path)
    return ds


def pose(cfg: dict, spec: RunSpec, wall_path: str | None, settings: TimeSettings, mesh, cell_tags,
         facet_tags) -> pipeline.Posed:
    """The rung on the run's mesh: the wall motion (read from `wall_path`, or solved), the urine alone on the
    fluid submesh, the quasi-static stent on the stent submesh, the probes and the one-way diagnostics (which refuse
    the run where the urine's pressure on the wall leaves the one the wall assumed: WallPressureRefused)."""
    if wall_path:
        history = WallHistory.from_dataset(open_netcdf(wall_path, WALL_MOTION), cfg, settings.end, settings.dt)
        log.info("wall (r-z) motion read from %s (%d steps, solved in %.1f s)", wall_path, len(history.time) - 1,
                 history.wall_time)
    else:
        history = wall_history(cfg, settings.end, settings.dt)

    axisymmetric = spec.symmetry == "axisymmetric"
    pb, fluid, motion = fluid_problem(cfg, mesh, cell_tags, facet_tags, history, axisymmetric)

    g = UreterGeometry.from_config(cfg)
    model = StentModel.from_config(cfg, spec.model)
    z = np.linspace(0.0, g.length, N_LINE)
    stent = None
    if model.stent and not axisymmetric:
        _, _, stent_material = materials(cfg)
        stent = QuasiStaticStent(extract(mesh, cell_tags, facet_tags, [tags.STENT]), stent_material, pb,
                                 spec.symmetry != "full", g.stent_probe_points(z))
    obs = UreterProbes(pb, cfg, model, spec.symmetry, cfg["time"]["probe_times"], wall=RecordedWall(history, z),
                       stent=stent)
    diag = OneWayDiagnostics(pb, cfg, stent)

    def attrs() -> dict:
        extra = {
            # the wall's solve time, in this run or in the shared wall_motion job (wall_motion_file)
            "wall_solve_time_s": round(history.wall_time, 2),
            "wall_motion_file": str(wall_path or ""),
            "one_way_mesh_motion": motion.used,
            "one_way_mesh_motion_rule": motion.rule,
            "one_way_predicted_min_jacobian": motion.algebraic.value,
            "one_way_predicted_min_jacobian_time": motion.algebraic.time,
            "one_way_predicted_extension_min_jacobian": motion.extension.value,
            "one_way_predicted_extension_min_jacobian_time": motion.extension.time,
            "one_way_mesh_motion_boundary_mismatch": pb.mesh_motion_mismatch,
            "one_way_max_wall_pressure_deviation": diag.max_wall_pressure_deviation,
            "one_way_peristaltic_peak_traction": cfg["peristalsis"]["peak_traction"],
            # the urine pressure the wall assumed against the one the urine solve found (OneWayDiagnostics)
            "one_way_wall_pressure_posed": int(wall_pressure_posed(cfg)),
            "one_way_wall_pressure_mismatch": diag.mismatch[0],
            "one_way_wall_pressure_mismatch_time": diag.mismatch[1],
            "one_way_wall_pressure_mismatch_z": diag.mismatch[2],
            "one_way_wall_pressure_tolerance": diag.limit,
        }
        if stent is not None:
            extra.update(one_way_max_stent_displacement=diag.max_stent_displacement,
                         one_way_hole_diameter=g.hole_radius * 2, stent_solve_time_s=round(stent.wall_time, 2))
        return extra

    def summary() -> str:
        return (f" (max |p - p_ref| on the wall {diag.max_wall_pressure_deviation:.1f} Pa vs load "
                f"{cfg['peristalsis']['peak_traction']:.0f} Pa; the wall's assumed urine pressure off the urine's by "
                f"{diag.mismatch[0]:.1f} Pa"
                + (f"; max stent displacement {diag.max_stent_displacement:.2e} m vs hole {2 * g.hole_radius:.1e} m"
                   if stent is not None else "") + ")")

    return pipeline.Posed(
        pb, obs, lambda q: oneway_parts(pb, stent, q, obs.surface if obs.has_stent else None),
        solver=(f"one-way: r-z wall (Mooney-Rivlin, BDF2) -> urine alone on the fluid submesh (ALE "
                f"P2-P1, {pb.mesh_motion_solver} mesh motion, BDF2, Newton + {pb.options.linear_solver}) -> "
                f"quasi-static linear stent (LU once)"),
        observers=[diag], attrs=attrs, summary=summary,
        description=f" ({fluid.mesh.topology.index_map(fluid.mesh.topology.dim).size_global} fluid)")


def run(cfg: dict, spec: RunSpec, out_path: str, checkpoint_path: str | None = None, wall_path: str | None = None):
    """One-way solve of one model on one mesh (serial); writes the same probe dataset as the fully
    coupled run (ureterfsi.study.coupled.run), with fidelity "one_way" and the one-way diagnostics. wall_path: a
    wall_motion dataset (write_wall_motion) to read instead of solving the wall."""
    if MPI.COMM_WORLD.size > 1:
        raise SystemExit("the one-way rung runs on one process (fidelity one_way); use fully_coupled under MPI")
    if one_way_unposable(cfg):
        raise SystemExit(one_way_unposable(cfg))
    return pipeline.run(cfg, spec, out_path, checkpoint_path, "one_way", partial(pose, cfg, spec, wall_path), wall_path)


class WallPressureRefused(SolveFailure):
    """The urine's mean pressure on the wall left the pressure the one-way wall assumed by more than
    ends.one_way_pressure_tolerance x peristalsis.peak_traction (end conditions posed): the run stops there."""


class OneWayDiagnostics(Observer):
    """What the one-way rung leaves out, measured as it runs: the largest |p - p_ref| of the urine on the
    ureter wall, the largest stent displacement (a motion the urine does not see), and the largest difference
    between the urine's mean pressure on the wall per z-slab (one wall thickness long: the wall averages a load
    over about its thickness; the mean of the pressure nodes in the slab) and the pressure the wall assumed there,
    p_ref + config.end_pressures.wall_pressure (`mismatch`: Pa, its time, its slab's centre z). With an end
    condition posed the run is refused (WallPressureRefused) once that difference exceeds
    ends.one_way_pressure_tolerance x peristalsis.peak_traction (`limit`, Pa); with both ends open (the paper's
    one-way wall, p_ref alone assumed) it is recorded only. Registered after UreterProbes, which updates the
    stent."""

    def __init__(self, pb: MonolithicFSI, cfg: dict, stent: QuasiStaticStent | None):
        P, pmap = pb.sub("pressure").collapse()
        fdim = pb.mesh.topology.dim - 1
        local = fem.locate_dofs_topological(P, fdim, pb.scene.facet_tags.find(tags.FLUID_URETER))
        self.dofs = np.asarray(pmap)[local]
        z = P.tabulate_dof_coordinates()[local, 1 if pb.scene.axisymmetric else 2]
        g = cfg["geometry"]
        n = max(1, int(round(g["length"] / g["ureter_wall_thickness"])))
        self.slab = np.minimum((z / g["length"] * n).astype(int), n - 1)
        self.counts = np.bincount(self.slab, minlength=n)
        self.z_slab = (np.arange(n) + 0.5) * g["length"] / n
        self.assumed = wall_pressure(cfg)
        self.posed = wall_pressure_posed(cfg)
        self.limit = cfg["ends"]["one_way_pressure_tolerance"] * cfg["peristalsis"]["peak_traction"]
        self.pb, self.p_ref, self.stent = pb, cfg["fluid"]["reference_pressure"], stent
        self.max_wall_pressure_deviation, self.max_stent_displacement = 0.0, 0.0
        self.mismatch = (0.0, 0.0, 0.0)

    def observe(self, problem, step):
        if self.dofs.size:
            p = self.pb.x.x.array[self.dofs]
            dev = float(np.max(np.abs(p - self.p_ref)))
            self.max_wall_pressure_deviation = max(self.max_wall_pressure_deviation, dev)
            filled = self.counts > 0
            mean = np.bincount(self.slab, weights=p, minlength=self.counts.size)[filled] / self.counts[filled]
            z = self.z_slab[filled]
            diff = np.abs(mean - self.p_ref - np.array([self.assumed(zk, problem.time) for zk in z]))
            k = int(np.argmax(diff))
            if diff[k] > self.mismatch[0]:
                self.mismatch = (float(diff[k]), float(problem.time), float(z[k]))
            if self.posed and diff[k] > self.limit:
                raise WallPressureRefused(
                    f"ends.one_way_pressure_tolerance: at t = {problem.time:g} s the urine's mean pressure on the wall "
                    f"at z = {z[k]:.4g} m differs from the one the one-way wall assumed by {diff[k]:.4g} Pa > "
                    f"{self.limit:.4g} Pa (the tolerance x peristalsis.peak_traction); use fidelity fully_coupled")
        if self.stent is not None:
            u = self.stent.u.x.array.reshape(-1, 3)
            self.max_stent_displacement = max(self.max_stent_displacement, float(np.linalg.norm(u, axis=1).max()))

    def state(self):
        return {"p": self.max_wall_pressure_deviation, "u": self.max_stent_displacement, "mismatch": self.mismatch}

    def load_state(self, state):
        self.max_wall_pressure_deviation, self.max_stent_displacement = state["p"], state["u"]
        self.mismatch = tuple(state["mismatch"])
