"""One run of the ureter study: mesh + configuration -> fully coupled solve -> probe dataset (netCDF).

Probes (paper §3, Figs. 3-10, and beyond):
  every step   outlet/inlet volumetric flux, mean axial outlet velocity (the paper's measure), maximum
               von Mises stress over the stent and where it occurs, fluid volume, flux through every
               side hole, maximum wall displacement, Newton iterations;
  probe times  von Mises along the probe line (r = 0.75 mm from the stent axis, plane y = 0, away from the
               holes), ureter outer-wall radial displacement vs z, velocity along the hole axis (y, or x
               for a rotated pair) across the outlet-most hole at mid-wall radius.
Every variable carries CF `units` and `long_name`; the dataset carries provenance.
"""
from __future__ import annotations

import json
import logging
import time as _time
from dataclasses import dataclass

import numpy as np
import ufl
import xarray as xr
from dolfinx import fem
from dolfinx.fem import petsc as fem_petsc
from dolfinx.mesh import compute_midpoints
from mpi4py import MPI

from . import tags
from .config import run_sections
from .fsi import Observer, SolverOptions, TimeIntegrator, TimeSettings
from .fsi import physics
from .fsi.problem import MonolithicFSI
from .fields import coupled_parts, field_writer
from .geometry import StentModel, UreterGeometry, hole_pair_axes, hole_pair_positions
from .probes import CellField, PointProbe, assemble_scalar, flux_volume_forms, inside_radius, von_mises
from .metadata import cf_meta, write_netcdf
from .provenance import provenance_attrs
from .scenes.ureter import pulse_centre, ureter_scene

log = logging.getLogger("ureterfsi.study")

FIDELITIES = ("fully_coupled", "one_way")   # rungs of the fidelity ladder a run can use
N_LINE, N_HOLE = 201, 21


@dataclass
class RunSpec:
    model: str
    level: str
    symmetry: str
    mesh_path: str
    end: float | None = None       # override of time.end (short test runs)
    dt: float | None = None        # override of time.dt


def solver_options(cfg: dict) -> SolverOptions:
    s = cfg["solver"]
    return SolverOptions(mesh_motion=s["mesh_motion"], mesh_stiffening=s["mesh_stiffening"],
                         newton_rtol=s["newton_rtol"], newton_atol=s["newton_atol"],
                         newton_max_iterations=s["newton_max_iterations"], predictor=s["predictor"],
                         linear_solver=s["linear_solver"],
                         reuse_jacobian=s["reuse_jacobian"], reuse_contraction=s["reuse_contraction"],
                         mesh_motion_direct_max_unknowns=int(s["mesh_motion_direct_max_unknowns"]),
                         krylov_rtol=s["krylov_rtol"])


class CoupledWall:
    """Ureter outer-wall radial displacement read from the coupled state (material points on the
    outer surface, x = R_o, y = 0, or (r, z) = (R_o, z))."""

    def __init__(self, pb: MonolithicFSI, z: np.ndarray, outer_radius: float):
        pts = (np.c_[np.full_like(z, outer_radius), z] if pb.scene.axisymmetric
               else np.c_[np.full_like(z, outer_radius), np.zeros_like(z), z])
        self.pb, self.probe = pb, PointProbe(pb.mesh, pts)
        self.displacement = fem.Function(pb.W.sub(pb.index["displacement"]).collapse()[0])

    def radial_displacement(self, time: float) -> np.ndarray:
        self.displacement.x.array[:] = self.pb.field("displacement").x.array
        return self.probe(self.displacement)[:, 0]


class CoupledStent:
    """Stent von Mises stress from the coupled state: sigma(u) of the stent material on the stent cells
    (Cauchy stress sigma = J^-1 P F^T for the geometrically nonlinear option, paper eq. 15)."""

    def __init__(self, pb: MonolithicFSI, probe_points: np.ndarray):
        stent = next(s.material for s in pb.scene.solids if tags.STENT in s.tags)
        u = pb.split()["displacement"]
        sigma = physics.elastic_first_piola(pb.ops, stent, u)
        if stent.kinematics != "linear":
            F = physics.deformation_gradient(pb.ops, u)
            sigma = sigma * F.T / ufl.det(F)
        self.von_mises = CellField(pb.mesh, von_mises(sigma), 1, pb.cells([tags.STENT]))
        self.probe = PointProbe(pb.mesh, probe_points)

    def update(self, pb: MonolithicFSI) -> None:
        self.von_mises.update()


class UreterProbes(Observer):
    """Records the study's quantities of interest after every accepted step.

    The fluid quantities come from the problem `pb` (fully coupled, or the fluid alone on its part of
    the mesh); the outer-wall displacement and the stent stress from `wall` and `stent` providers
    (default: read from the coupled state; the one-way rung passes its own, see ureterfsi.oneway).
    """

    def __init__(self, pb: MonolithicFSI, cfg: dict, model: StentModel, symmetry: str, probe_times,
                 wall=None, stent=None):
        self.pb, self.cfg, self.symmetry = pb, cfg, symmetry
        self.geom = g = UreterGeometry.from_config(cfg)
        self.axisymmetric = pb.scene.axisymmetric
        self.probe_times = list(probe_times)
        ops, mesh, comm = pb.ops, pb.mesh, pb.comm
        X, Xdot = pb.split(), pb.split(pb.x_dot)
        v, u, w = X["velocity"], X["displacement"], Xdot["displacement"]
        F = physics.deformation_gradient(ops, u)
        J = ufl.det(F)
        N = ops.normal()
        n_da = J * ufl.inv(F).T * N
        e_z = ufl.as_vector([0.0, 0.0, 1.0])
        rel = ops.vec(v) - ops.vec(w)
        ds, dx = pb.ds, pb.dx
        self.forms = {k: fem.form(f) for k, f in flux_volume_forms(pb).items()} | {
            "outlet_area": fem.form(ufl.sqrt(ufl.dot(n_da, n_da)) * ops.weight * ds(tags.OUTLET)),
            "outlet_axial_velocity_integral": fem.form(ufl.dot(ops.vec(v), e_z) * ufl.sqrt(ufl.dot(n_da, n_da))
                                                       * ops.weight * ds(tags.OUTLET)),
        }
        self.comm = comm
        self.fraction = {"full": 1.0, "half": 2.0, "quarter": 4.0, "axisymmetric": 1.0}[symmetry]

        z = np.linspace(0.0, g.length, N_LINE)
        self.z = z
        self.wall = wall or CoupledWall(pb, z, g.ureter_outer_radius)
        self.velocity = fem.Function(pb.W.sub(pb.index["velocity"]).collapse()[0])

        self.has_stent = model.stent and not self.axisymmetric
        if self.has_stent:
            xs = g.stent_offset
            self.stent = stent or CoupledStent(pb, g.stent_probe_points(z))
            # holes (z, side, axis 0 = x / 1 = y): the model keeps the + side of each cut plane (normal 0 = x, 1 = y;
            # half: x = 0, or y = 0 for an offset stent). A hole on a plane's normal axis has only its + side in the
            # model; a hole whose axis lies in a cut plane is cut in half by it (fraction 0.5).
            cut = {"full": (), "half": (1,) if xs else (0,), "quarter": (0, 1)}[symmetry]
            self.hole_z = hole_pair_positions(g, model)
            axes = hole_pair_axes(g, model)
            self.holes = [(zk, sd, int(a)) for zk, a in zip(self.hole_z, axes)
                          for sd in ([1.0] if a in cut else [1.0, -1.0])]
            self.hole_fraction = np.array([0.5 if 1 - a in cut else 1.0 for _, _, a in self.holes])
            Q = fem.FunctionSpace(mesh, ("DG", 0))
            Xc = ufl.SpatialCoordinate(mesh)
            R = ufl.sqrt((Xc[0] - xs) ** 2 + Xc[1] ** 2)
            e_r = ufl.as_vector([(Xc[0] - xs) / R, Xc[1] / R, 0.0])
            grad_chi = e_r / (g.stent_outer_radius - g.stent_inner_radius)
            # Q_k = int_channel J F^-1 (v - w) . Grad chi dX, chi = (R - r_i)/(r_o - r_i), R from the stent axis: flux through
            # any surface R = const of the channel (exact for a divergence-free field); outward positive.
            self.hole_form = fem.form(J * ufl.dot(ufl.inv(F) * rel, grad_chi) * ufl.TestFunction(Q) * dx(tags.FLUID))
            self.hole_vec = fem_petsc.create_vector(self.hole_form)
            n_local = mesh.topology.index_map(mesh.topology.dim).size_local
            fluid = pb.cells([tags.FLUID])
            fluid = fluid[fluid < n_local]
            mid = compute_midpoints(mesh, mesh.topology.dim, fluid)
            d = np.c_[mid[:, 0] - xs, mid[:, 1]]
            Rm = np.hypot(d[:, 0], d[:, 1])
            chan = (Rm > g.stent_inner_radius) & (Rm < g.stent_outer_radius)
            self.hole_cells = []
            for zk, sd, a in self.holes:   # a channel cell on the hole's own axis, on its side
                sel = (chan & (np.abs(mid[:, 2] - zk) < 2 * g.hole_radius) & (np.sign(d[:, a]) == sd)
                       & (np.abs(d[:, a]) > np.abs(d[:, 1 - a])))
                self.hole_cells.append(Q.dofmap.list.array[fluid[sel]])
            k = int(np.argmax(self.hole_z))
            zh, self.hole_probe_axis = float(self.hole_z[k]), int(axes[k])
            s = np.linspace(-g.hole_radius, g.hole_radius, N_HOLE)
            self.hole_s = s
            on_axis = np.zeros((s.size, 2))
            on_axis[:, self.hole_probe_axis] = g.probe_radius
            self.hole_probe = PointProbe(mesh, np.c_[xs + on_axis[:, 0], on_axis[:, 1], zh + s])
            self.outlet_hole_z = zh
            # the stent-lumen share of the end-face fluxes (R < mid-wall radius from the stent axis: inside the stent)
            lumen = inside_radius(mesh, g.probe_radius, xs)
            self.forms["outlet_lumen_flux"] = fem.form(lumen * ufl.dot(rel, n_da) * ops.weight * ds(tags.OUTLET))
            self.forms["inlet_lumen_flux"] = fem.form(-lumen * ufl.dot(rel, n_da) * ops.weight * ds(tags.INLET))
        self.series = {k: [] for k in self.series_names()}
        self.snapshots = {k: [] for k in self.snapshot_names()}
        self.snapshot_times = []

    def series_names(self):
        names = ["time", "outlet_flux", "inlet_flux", "outlet_mean_axial_velocity", "fluid_volume",
                 "max_wall_displacement"]
        if self.has_stent:
            names += ["stent_max_von_mises", "stent_max_von_mises_x", "stent_max_von_mises_y",
                      "stent_max_von_mises_z", "hole_flux", "outlet_lumen_flux", "inlet_lumen_flux"]
        return names

    def snapshot_names(self):
        names = ["wall_radial_displacement"]
        if self.has_stent:
            names += ["stent_von_mises_line", "hole_velocity_y"]
        return names

    def observe(self, pb: MonolithicFSI, step: int) -> None:
        val = {k: assemble_scalar(f, self.comm) for k, f in self.forms.items()}
        s = self.series
        s["time"].append(pb.time)
        s["outlet_flux"].append(self.fraction * val["outlet_flux"])
        s["inlet_flux"].append(self.fraction * val["inlet_flux"])
        s["outlet_mean_axial_velocity"].append(val["outlet_axial_velocity_integral"] / val["outlet_area"])
        s["fluid_volume"].append(self.fraction * val["fluid_volume"])
        wall = self.wall.radial_displacement(pb.time)
        s["max_wall_displacement"].append(float(np.nanmax(np.abs(wall))))
        if self.has_stent:
            s["outlet_lumen_flux"].append(self.fraction * val["outlet_lumen_flux"])
            s["inlet_lumen_flux"].append(self.fraction * val["inlet_lumen_flux"])
            self.stent.update(pb)
            vmax, where = self.stent.von_mises.maximum()
            s["stent_max_von_mises"].append(vmax)
            for c, name in zip(where, "xyz"):
                s[f"stent_max_von_mises_{name}"].append(c)
            vec = self.hole_vec
            with vec.localForm() as loc:
                loc.set(0.0)
            fem_petsc.assemble_vector(vec, self.hole_form)
            arr = vec.array
            local = np.array([arr[c[c < arr.size]].sum() for c in self.hole_cells])
            flux = _allreduce_sum(self.comm, local)
            s["hole_flux"].append((flux / self.hole_fraction).tolist())
        if any(abs(pb.time - t) < 1e-9 for t in self.probe_times):
            self.snapshot_times.append(pb.time)
            self.snapshots["wall_radial_displacement"].append(wall.tolist())
            if self.has_stent:
                self.snapshots["stent_von_mises_line"].append(
                    self.stent.probe(self.stent.von_mises.function)[:, 0].tolist())
                self.velocity.x.array[:] = pb.field("velocity").x.array
                self.snapshots["hole_velocity_y"].append(
                    self.hole_probe(self.velocity)[:, self.hole_probe_axis].tolist())

    def state(self) -> dict:
        return {"series": self.series, "snapshots": self.snapshots, "snapshot_times": self.snapshot_times}

    def load_state(self, state: dict) -> None:
        self.series, self.snapshots = state["series"], state["snapshots"]
        self.snapshot_times = state["snapshot_times"]


def _allreduce_sum(comm, arr):
    out = np.zeros_like(arr)
    comm.Allreduce(np.ascontiguousarray(arr), out, op=MPI.SUM)
    return out


def _cf(da: xr.DataArray, name: str) -> xr.DataArray:
    units, long_name = cf_meta(name)
    da.attrs.update(units=units, long_name=long_name)
    return da


def probes_dataset(obs: UreterProbes, records, cfg: dict, spec: RunSpec, extra_attrs: dict,
                   fidelity: str = "fully_coupled") -> xr.Dataset:
    """Assemble the run's probe records into a CF-annotated dataset."""
    t = np.asarray(obs.series["time"])
    ds = xr.Dataset(coords={"time": _cf(xr.DataArray(t, dims="time"), "time")})
    for name in obs.series_names():
        if name in ("time", "hole_flux"):
            continue
        ds[name] = _cf(xr.DataArray(np.asarray(obs.series[name]), dims="time"), name)
    ds["pulse_centre"] = _cf(xr.DataArray(pulse_centre(cfg["peristalsis"], t), dims="time"), "pulse_centre")
    ds = ds.assign_coords(z=_cf(xr.DataArray(obs.z, dims="z"), "z"),
                          probe_time=_cf(xr.DataArray(np.asarray(obs.snapshot_times), dims="probe_time"),
                                         "probe_time"))
    for name in obs.snapshot_names():
        dim = "hole_offset" if name == "hole_velocity_y" else "z"
        width = len(obs.hole_s) if dim == "hole_offset" else len(obs.z)
        data = np.asarray(obs.snapshots[name], dtype=float).reshape(len(obs.snapshot_times), width)
        ds[name] = _cf(xr.DataArray(data, dims=("probe_time", dim)), name)
    if obs.has_stent:
        ds = ds.assign_coords(hole_offset=_cf(xr.DataArray(obs.hole_s, dims="hole_offset"), "hole_offset"),
                              hole_z=_cf(xr.DataArray([h[0] for h in obs.holes], dims="hole"), "hole_z"),
                              hole_side=_cf(xr.DataArray([h[1] for h in obs.holes], dims="hole"), "hole_side"),
                              hole_axis=_cf(xr.DataArray([h[2] for h in obs.holes], dims="hole"), "hole_axis"))
        ds["hole_flux"] = _cf(xr.DataArray(np.asarray(obs.series["hole_flux"]), dims=("time", "hole")), "hole_flux")
        ds.attrs["outlet_hole_z"] = obs.outlet_hole_z
    steps = {"step_time": [r.time for r in records], "step_dt": [r.dt for r in records],
             "newton_iterations": [r.newton_iterations for r in records],
             "newton_residual": [r.residual for r in records],
             "min_ale_jacobian": [r.min_ale_jacobian for r in records],
             "step_wall_time": [r.wall_time for r in records]}
    for name, values in steps.items():
        ds[name] = _cf(xr.DataArray(np.asarray(values), dims="step"), name)
    import resource

    # peak resident memory of this process (Linux reports KiB), rank 0 under MPI
    peak = round(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0, 1)
    ds.attrs.update(provenance_attrs(cfg, model=spec.model, mesh_level=spec.level, symmetry=spec.symmetry,
                                     fidelity=fidelity, peak_memory_mib=peak, **extra_attrs))
    ds.attrs["Conventions"] = "CF-1.8"
    ds.attrs["title"] = f"ureterfsi probes, model {spec.model}, mesh {spec.level} ({spec.symmetry})"
    return ds


def time_settings(cfg: dict, spec: RunSpec, checkpoint_path: str | None, fidelity: str = "fully_coupled",
                  wall_path: str | None = None) -> TimeSettings:
    """Time stepping of a run: config `time` with the run's end/dt overrides, checkpoints if a path is given
    (bound to the run's identity, run_identity)."""
    tcfg = cfg["time"]
    settings = TimeSettings(end=spec.end or tcfg["end"], dt=spec.dt or tcfg["dt"], output_times=tcfg["probe_times"],
                            max_halvings=cfg["solver"]["max_step_halvings"],
                            checkpoint_interval=tcfg["checkpoint_interval"] if checkpoint_path else 0,
                            checkpoint_path=checkpoint_path)
    if checkpoint_path:
        settings.identity = run_identity(cfg, spec, fidelity, settings.end, settings.dt, wall_path)
    return settings


def _flatten(prefix: str, value, out: dict) -> None:
    if isinstance(value, dict):
        for k, v in value.items():
            _flatten(f"{prefix}.{k}" if prefix else str(k), v, out)
    else:
        out[prefix] = json.dumps(value, sort_keys=True)


def run_identity(cfg: dict, spec: RunSpec, fidelity: str, end: float, dt: float, wall_path: str | None = None) -> dict:
    """What determines a run, component -> value (TimeSettings.identity): every key of the configuration
    sections it reads (ureterfsi.config.run_sections), the run's model, mesh level, symmetry, fidelity,
    end and dt, the SHA-256 of the mesh file (and of the wall-motion file of a one-way run), and the
    versions of ureterfsi and dolfinx."""
    import dolfinx

    from . import __version__
    from .checked_io import sha256_file

    out: dict = {}
    sections = run_sections(cfg, spec.model)
    _flatten(f"models.{spec.model}", sections.pop("model"), out)
    _flatten("", sections, out)
    out.update({"run.model": spec.model, "run.level": spec.level, "run.symmetry": spec.symmetry,
                "run.fidelity": fidelity, "run.end": repr(float(end)), "run.dt": repr(float(dt)),
                "mesh_sha256": sha256_file(spec.mesh_path),
                "version.ureterfsi": __version__, "version.dolfinx": dolfinx.__version__})
    if wall_path:
        out["wall_motion_sha256"] = sha256_file(wall_path)
    return out


def integrate_from_rest(pb: MonolithicFSI, settings: TimeSettings, observers,
                        reference_pressure: float) -> TimeIntegrator:
    """Urine at rest at the reference pressure (steady solve, paper §2.4), then time steps to the end;
    a run with a checkpoint resumes from it instead. The integrator holds the step records; remove its
    checkpoint once the run's output is written."""
    integrator = TimeIntegrator(pb, settings, observers)
    if not integrator.has_checkpoint():
        # Newton starts from p = p_ref: for the urine alone (walls at rest) that is the solution, so the
        # steady solve ends after one residual (no Jacobian, no factorisation)
        pb.fill("pressure", reference_pressure)
        its, hist = pb.solve_steady()
        log.info("initial state: urine at rest at the reference pressure, %d Newton iterations, residual %.2e",
                 its, hist[-1])
    integrator.run()
    return integrator


def run(cfg: dict, spec: RunSpec, out_path: str, checkpoint_path: str | None = None) -> xr.Dataset:
    """Fully coupled solve of one model on one mesh; writes the probe dataset atomically."""
    from mpi4py import MPI as _MPI

    from .mesh import load_mesh

    wall0 = _time.perf_counter()
    comm = _MPI.COMM_WORLD
    mesh, cell_tags, facet_tags = load_mesh(spec.mesh_path, comm)
    scene = ureter_scene(cfg, mesh, cell_tags, facet_tags, axisymmetric=spec.symmetry == "axisymmetric")
    pb = MonolithicFSI(scene, solver_options(cfg))
    ndofs = pb.W.dofmap.index_map.size_global * pb.W.dofmap.index_map_bs
    ncells = mesh.topology.index_map(mesh.topology.dim).size_global
    log.info("model %s, mesh %s (%s): %d cells, %d dofs, %d processes, setup %.1f s", spec.model, spec.level,
             spec.symmetry, ncells, ndofs, comm.size, _time.perf_counter() - wall0)
    settings = time_settings(cfg, spec, checkpoint_path)
    obs = UreterProbes(pb, cfg, StentModel.from_config(cfg, spec.model), spec.symmetry, cfg["time"]["probe_times"])
    fields = field_writer(cfg, out_path, lambda q: coupled_parts(pb, obs.stent if obs.has_stent else None, q,
                                                                 cfg["fluid"]["reference_pressure"]),
                          settings.end, comm)
    integrator = integrate_from_rest(pb, settings, [obs] + ([fields] if fields else []),
                                     cfg["fluid"]["reference_pressure"])
    records = integrator.records
    field_attrs = fields.finish(out_path) if fields else {}
    wall = _time.perf_counter() - wall0
    ds = probes_dataset(obs, records, cfg, spec, field_attrs | {
        "cells": ncells, "dofs": ndofs, "processes": comm.size, "wall_time_s": round(wall, 2),
        "time_step_s": settings.dt, "end_time_s": settings.end,
        "solver": f"monolithic ALE, P2-P2-P1-P0, BDF2, Newton + {cfg['solver']['linear_solver']}",
        "timings": {k: round(v, 2) for k, v in pb.timings.items()}, "counters": dict(pb.counters)})
    if comm.rank == 0:
        write_netcdf(ds, out_path)
    comm.Barrier()
    integrator.remove_checkpoint()
    log.info("done in %.1f s -> %s", wall, out_path)
    return ds


def configure_logging(stream=None) -> None:
    """Progress lines of the engine and the study on rank 0 (warnings from every rank)."""
    from mpi4py import MPI as _MPI

    rank = _MPI.COMM_WORLD.rank
    handler = logging.StreamHandler(stream)
    handler.setFormatter(logging.Formatter("%(asctime)s %(name)s: %(message)s", "%H:%M:%S"))
    for name in ("ureterfsi",):
        lg = logging.getLogger(name)
        lg.handlers[:] = [handler]
        lg.setLevel(logging.INFO if rank == 0 else logging.WARNING)
        lg.propagate = False


def main(argv=None) -> int:
    import argparse
    import sys

    from mpi4py import MPI as _MPI

    from .checked_io import BadFile
    from .config import ConfigError, load_config, load_config_files, run_config
    from .fsi import SolveFailure

    ap = argparse.ArgumentParser(prog="python -m ureterfsi.study",
                                 description="FSI solve of one stent model on one mesh (fully coupled or one-way).")
    ap.add_argument("--config", nargs="+", default=["config/config.yaml"], help="config file and overlays")
    ap.add_argument("--config-json", default=None, help="the whole configuration as JSON")
    ap.add_argument("--run-config", default=None,
                    help="the sections this solve reads as JSON (ureterfsi.config.run_sections; rule solve)")
    ap.add_argument("--model", required=True)
    ap.add_argument("--level", required=True)
    ap.add_argument("--symmetry", required=True)
    ap.add_argument("--mesh", required=True, help="gmsh .msh file of the model")
    ap.add_argument("--out", required=True, help="netCDF output")
    ap.add_argument("--checkpoint", default=None, help="checkpoint path (resumes if present)")
    ap.add_argument("--end", type=float, default=None, help="override time.end (s)")
    ap.add_argument("--dt", type=float, default=None, help="override time.dt (s)")
    ap.add_argument("--wall", default=None,
                    help="one_way: the wall-motion dataset to read (rule wall_motion, ureterfsi.oneway.write_wall_motion) "
                         "instead of solving the wall")
    ap.add_argument("--fidelity", choices=FIDELITIES, default="fully_coupled",
                    help="fully_coupled (monolithic ALE FSI) or one_way (wall -> urine -> stent, ureterfsi.oneway)")
    args = ap.parse_args(argv)
    configure_logging()
    try:
        if args.run_config:
            with open(args.run_config) as fh:
                cfg = run_config(json.load(fh), args.model)
        elif args.config_json:
            with open(args.config_json) as fh:
                cfg = load_config(json.load(fh))
        else:
            cfg = load_config_files(args.config)
    except ConfigError as err:
        print(err, file=sys.stderr)
        return 2
    spec = RunSpec(args.model, args.level, args.symmetry, args.mesh, args.end, args.dt)
    try:
        if args.fidelity == "one_way":
            from . import oneway

            oneway.run(cfg, spec, args.out, args.checkpoint, wall_path=args.wall)
        else:
            run(cfg, spec, args.out, args.checkpoint)
    except (BadFile, SolveFailure) as err:
        if _MPI.COMM_WORLD.rank == 0:
            print(err, file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
