"""The study's probes of a ureter run and its probe dataset (netCDF).

Probes (paper §3, Figs. 3-10, and beyond):
  every step   outlet/inlet volumetric flux, area-mean urine pressure on the outlet/inlet end faces, mean
               axial outlet velocity (the paper's measure), maximum
               von Mises stress over the stent and where it occurs, fluid volume, net flux and gross exchange
               through every side hole, wall shear stress on the stent's outer surface, lumen and hole walls
               (ureterfsi.study.stent_surface), maximum wall displacement, Newton iterations;
  run end      TAWSS, OSI and low-WSS area fraction of those surfaces, per hole its exchange volumes and label;
  probe times  von Mises along the probe line (r = 0.75 mm from the stent axis, plane y = 0, away from the
               holes), ureter outer-wall radial displacement vs z (the wall probe line: the reference outer
               surface R_o(z) on the meridian y = 0, the same line on both rungs), velocity along the hole
               axis (y, or x for a rotated pair) across the outlet-most hole at mid-wall radius.
Every variable carries CF `units` and `long_name`; the dataset carries provenance.
"""
from __future__ import annotations

import resource

import numpy as np
import ufl
import xarray as xr
from dolfinx import fem
from dolfinx.mesh import compute_midpoints

from ureterfsi.mesh import tags
from ..fsi import Observer
from ..fsi import physics
from ..fsi.problem import MonolithicFSI
from ureterfsi.fsi.wall_shear import ChannelFlux
from ureterfsi.mesh.geometry import SYMMETRY_FRACTION, StentModel, UreterGeometry, hole_pair_axes, hole_pair_positions
from ureterfsi.data.cf import cf_meta
from ureterfsi.fsi.probes import (CellField, PointProbe, assemble_scalar, cut_flux_forms, end_face_pressure_forms,
                                  flux_volume_forms, inside_radius, surface_line_points, von_mises)
from ureterfsi.data.provenance import provenance_attrs
from ..scenes.ureter import pulse_centre
from .options import RunSpec
from .stent_surface import StentSurface, hole_index

N_LINE, N_HOLE = 201, 21


class CoupledWall:
    """Ureter outer-wall radial displacement read from the coupled state at the material points of the outer
    surface on the meridian y = 0, x > 0 (or the r-z outer boundary) at each z: u_x (u_r) where the mesh's own
    outer facets meet that line (ureterfsi.fsi.probes.surface_line_points), so on the surface R_o(z) a stricture
    narrows, and in every symmetry (a half or full mesh need not have a mesh edge on that line)."""

    def __init__(self, pb: MonolithicFSI, z: np.ndarray):
        pts, cells = surface_line_points(pb.mesh, pb.scene.facet_tags.find(tags.URETER_OUTER), z,
                                         pb.scene.axisymmetric)
        self.pb, self.probe = pb, PointProbe(pb.mesh, pts[:, :pb.mesh.geometry.dim], cells)
        missing = self.probe.missing
        if missing.size:
            raise ValueError(f"{missing.size} of {len(z)} wall probe points (z = {z[missing[0]]:.6g} m, ...) meet no "
                             f"outer-wall facet on the meridian y = 0, x > 0")
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
        stent_cells = pb.cells([tags.STENT])
        self.von_mises = CellField(pb.mesh, von_mises(sigma), 1, stent_cells)
        self.probe = PointProbe(pb.mesh, probe_points, within=stent_cells)

    def update(self, pb: MonolithicFSI) -> None:
        self.von_mises.update()


class UreterProbes(Observer):
    """Records the study's quantities of interest after every accepted step.

    The fluid quantities come from the problem `pb` (fully coupled, or the fluid alone on its part of
    the mesh); the outer-wall displacement and the stent stress from `wall` and `stent` providers
    (default: read from the coupled state; the one-way rung passes its own, see ureterfsi.study.oneway).
    """

    obstruction_z: float | None = None   # the obstruction's centre (a stented model), where the flow past it is probed

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
        ds = pb.ds
        self.forms = {k: fem.form(f) for k, f in (flux_volume_forms(pb, tags.INLET, tags.OUTLET)
                                                 | end_face_pressure_forms(pb, tags.INLET, tags.OUTLET)).items()} | {
            "outlet_area": fem.form(ufl.sqrt(ufl.dot(n_da, n_da)) * ops.weight * ds(tags.OUTLET)),
            "outlet_axial_velocity_integral": fem.form(ufl.dot(ops.vec(v), e_z) * ufl.sqrt(ufl.dot(n_da, n_da))
                                                       * ops.weight * ds(tags.OUTLET)),
        }
        self.comm = comm
        self.fraction = 1.0 / SYMMETRY_FRACTION[symmetry]

        z = np.linspace(0.0, g.length, N_LINE)
        self.z = z
        self.wall = wall or CoupledWall(pb, z)
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
            Xc = ufl.SpatialCoordinate(mesh)
            R = ufl.sqrt((Xc[0] - xs) ** 2 + Xc[1] ** 2)
            e_r = ufl.as_vector([(Xc[0] - xs) / R, Xc[1] / R, 0.0])
            grad_chi = e_r / (g.stent_outer_radius - g.stent_inner_radius)
            # net and gross flux through the holes, chi = (R - r_i)/(r_o - r_i), R from the stent axis (ChannelFlux):
            # over the channel cells of each hole (on its own axis, its side); outward positive
            n_local = mesh.topology.index_map(mesh.topology.dim).size_local
            fluid = pb.cells([tags.FLUID])
            fluid = fluid[fluid < n_local]
            mid = compute_midpoints(mesh, mesh.topology.dim, fluid)
            Rm = np.hypot(mid[:, 0] - xs, mid[:, 1])
            chan = (Rm > g.stent_inner_radius) & (Rm < g.stent_outer_radius)
            near = hole_index(mid, self.holes, xs, g.hole_radius)
            if np.any(chan & (near < 0)):
                i = np.flatnonzero(chan & (near < 0))[0]
                raise ValueError(f"hole channels: a fluid cell inside the stent wall at {mid[i].round(6).tolist()} m "
                                 f"is in no side hole")
            self.hole_channels = ChannelFlux(pb, grad_chi, [fluid[chan & (near == k)] for k in range(len(self.holes))])
            self.surface = StentSurface(pb, cfg, g, self.holes)
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
            # past the obstruction (a complete occlusion, else a stricture): the flux through its centre's plane and
            # the stent lumen's part of it (R < mid-wall radius)
            self.obstruction_z = g.obstruction_centre
            if self.obstruction_z is not None:
                cut, self._cut_indicator = cut_flux_forms(pb, self.obstruction_z, g.probe_radius, xs)
                self.forms |= {"obstruction_flux": fem.form(cut["cut_flux"]),
                               "obstruction_lumen_flux": fem.form(cut["cut_inside_flux"])}
        self.series = {k: [] for k in self.series_names()}
        self.snapshots = {k: [] for k in self.snapshot_names()}
        self.snapshot_times = []

    def series_names(self):
        names = ["time", "outlet_flux", "inlet_flux", "outlet_mean_pressure", "inlet_mean_pressure",
                 "outlet_mean_axial_velocity", "fluid_volume", "fluid_volume_rate", "max_wall_displacement"]
        if self.has_stent:
            names += ["stent_max_von_mises", "stent_max_von_mises_x", "stent_max_von_mises_y",
                      "stent_max_von_mises_z", "hole_flux", "outlet_lumen_flux", "inlet_lumen_flux",
                      "hole_gross_exchange", "stent_outer_wss", "stent_lumen_wss", "hole_wall_wss"]
            names += ["obstruction_flux", "obstruction_lumen_flux"] if self.obstruction_z is not None else []
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
        for end in ("outlet", "inlet"):
            s[f"{end}_mean_pressure"].append(val[f"{end}_pressure_integral"] / val[f"{end}_area"])
        s["outlet_mean_axial_velocity"].append(val["outlet_axial_velocity_integral"] / val["outlet_area"])
        s["fluid_volume"].append(self.fraction * val["fluid_volume"])
        s["fluid_volume_rate"].append(self.fraction * val["fluid_volume_rate"])
        wall = self.wall.radial_displacement(pb.time)
        s["max_wall_displacement"].append(float(np.nanmax(np.abs(wall))))
        if self.has_stent:
            s["outlet_lumen_flux"].append(self.fraction * val["outlet_lumen_flux"])
            s["inlet_lumen_flux"].append(self.fraction * val["inlet_lumen_flux"])
            for k in ("obstruction_flux", "obstruction_lumen_flux"):
                if k in val:
                    s[k].append(self.fraction * val[k])
            self.stent.update(pb)
            vmax, where = self.stent.von_mises.maximum()
            s["stent_max_von_mises"].append(vmax)
            for c, name in zip(where, "xyz"):
                s[f"stent_max_von_mises_{name}"].append(c)
            net, gross = self.hole_channels()
            s["hole_flux"].append((net / self.hole_fraction).tolist())
            s["hole_gross_exchange"].append((gross / self.hole_fraction).tolist())
            for name, value in self.surface.observe(pb.time).items():
                s[name].append(value)
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
        return {"series": self.series, "snapshots": self.snapshots, "snapshot_times": self.snapshot_times,
                "stent_surface": self.surface.state() if self.has_stent else None}

    def load_state(self, state: dict) -> None:
        self.series, self.snapshots = state["series"], state["snapshots"]
        self.snapshot_times = state["snapshot_times"]
        if self.has_stent:
            self.surface.load_state(state["stent_surface"])


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
        if name in ("time", "hole_flux", "hole_gross_exchange", "hole_wall_wss"):
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
        for name in ("hole_flux", "hole_gross_exchange", "hole_wall_wss"):
            ds[name] = _cf(xr.DataArray(np.asarray(obs.series[name]).reshape(len(t), -1).T, dims=("hole", "time")),
                           name)
        summary = obs.surface.summary_variables(obs.comm, t, ds["hole_gross_exchange"].values, ds["hole_flux"].values)
        for name, (dims, values) in summary.items():
            ds[name] = _cf(xr.DataArray(values, dims=dims), name)
        ds.attrs["outlet_hole_z"] = obs.outlet_hole_z
        if obs.obstruction_z is not None:
            ds.attrs["obstruction_z"] = obs.obstruction_z
    steps = {"step_time": [r.time for r in records], "step_dt": [r.dt for r in records],
             "newton_iterations": [r.newton_iterations for r in records],
             "newton_residual": [r.residual for r in records],
             "min_ale_jacobian": [r.min_ale_jacobian for r in records],
             "step_wall_time": [r.wall_time for r in records]}
    for name, values in steps.items():
        ds[name] = _cf(xr.DataArray(np.asarray(values), dims="step"), name)
    # peak resident memory of this process (Linux reports KiB), rank 0 under MPI
    peak = round(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0, 1)
    ds.attrs.update(provenance_attrs(cfg, model=spec.model, mesh_level=spec.level, symmetry=spec.symmetry,
                                     fidelity=fidelity, peak_memory_mib=peak, **extra_attrs))
    ds.attrs["Conventions"] = "CF-1.8"
    ds.attrs["title"] = f"ureterfsi probes, model {spec.model}, mesh {spec.level} ({spec.symmetry})"
    return ds
