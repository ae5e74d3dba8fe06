"""Stability at the extremes (issue 5): a one-at-a-time parameter matrix around the baseline.

Two scenes:
- **r-z, fully coupled** (every axis but hole_elements): the stent-free model 1 in the axisymmetric r-z
  formulation (the same physics blocks as the 3D study: ALE Navier-Stokes, mixed Mooney-Rivlin wall,
  open ends, the travelling Gaussian pulse) over the whole 50 mm segment;
- **3D, one-way** (axis hole_elements, config `stability.holes`): how many elements a side hole needs is
  a 3D question. A stented model on its 3D quarter mesh whose hole size is set to hole_diameter / n,
  solved with the rung the hole figures use (ureterfsi.oneway: the urine alone on the fluid part of the
  mesh, the r-z wall motion prescribed, the stent rigid); the quantities below are those of the urine.
  (The fully coupled 3D model costs ~40 s per step on the coarse quarter mesh: 3 s per case would take
  hours.) n = 4 is the coarse default, the scene's own baseline.

Each case changes one quantity of the configuration's baseline (config `stability.axes`, SI units):

  time_step       s      time.dt
  mesh_level      -      mesh level of the r-z mesh (its number of cells is the plotted value)
  bulk_ratio      1      kappa / (C10 + C01): ureter.bulk_modulus scaled
  density_ratio   1      rho_wall / rho_urine: ureter.density scaled (added-mass regime)
  load_amplitude  Pa     peristalsis.peak_traction
  wave_speed      m s-1  peristalsis.speed (the run is stretched so the pulse travels the same distance)
  wave_width      m      peristalsis.width (in peristalsis.width_measure)
  viscosity       Pa s   fluid.dynamic_viscosity
  hole_elements   1      elements across a side-hole diameter: mesh.sizes.hole = hole_diameter / n at
                         stability.level (3D one-way scene)

and runs to `stability.end` (the paper's 3 s: the pulse centre crosses the segment and leaves it).

Recorded every accepted step by `StabilityObserver` (assembled on the reference mesh; in r-z with the
axisymmetric weight 2 pi r, so every value is that of the whole 3D tube; in 3D those of the symmetry
sector the mesh holds):
  kinetic energy  E = int_fluid 1/2 rho |v|^2 J + int_solid 1/2 rho0 |v|^2;
  elastic energy  int_solid W(F) (Mooney-Rivlin W_iso + kappa/2 (J - 1)^2, >= 0);
  external power  of the peristaltic load (int t . v), of the open-boundary normal stress and of the
                  prescribed (Dirichlet) motion: sum_i R_i v_i over the velocity dofs, R the residual
                  assembled without boundary conditions (the consistent reaction: the force the wall
                  exerts on the urine; zero for clamped ends and symmetry conditions);
  fluid volume    V = int_fluid J, the flux Q = Q_out - Q_in through the open ends and the volume
                  balance error |V(t) - V(0) + int_0^t Q| with the flux integrated by the step's own
                  BDF weights (the integration consistent with the scheme; the trapezoidal rule is not,
                  see tests/test_conservation.py), relative to the volume the wave displaces max|V - V0|;
  min ALE Jacobian, Newton iterations, step halvings (counted from the engine's retry warnings), wall time.

Limits (a case ends "failed" at the first one it hits, with a diagnosis naming the limit, the time and
the place; otherwise it is "stable"):
  newton          a step fails even after solver.max_step_halvings halvings (engine SolveFailure); the
                  place is the dof with the largest residual of the last Newton iterate;
  nan             the same with a non-finite residual, or a non-finite recorded quantity;
  ale_inversion   the minimum ALE Jacobian of the fluid mesh falls to stability.min_ale_jacobian (engine);
                  the place is the fluid vertex with the smallest Jacobian (places are given as (r, z),
                  r = sqrt(x^2 + y^2) in 3D);
  energy          E(t) > energy_safety * (E(0) + E_el(0) + W(t)), W(t) = int_0^t |P_load| + |P_open|
                  + |P_prescribed| dt. Physically E_kin + E_el changes by the net external work minus the
                  viscous and backflow dissipation, and E_el >= 0, so E(t) <= E(0) + E_el(0) + W(t); the
                  safety factor (default 10) leaves room for the discrete scheme (variable-step BDF2 is not
                  strictly energy-decreasing, the work is integrated by the rectangle rule). The place is
                  the node of the largest velocity;
  volume          the run ends but the volume balance error exceeds stability.volume_tolerance;
  wall_time       the case exceeds stability.max_wall_time (a budget, not a physical limit);
  exception       anything else (the message is kept): a case never crashes the matrix.
"""
from __future__ import annotations

import logging
import math
import re
import tempfile
import time as _time
from copy import deepcopy
from dataclasses import dataclass
from pathlib import Path

import netCDF4  # noqa: F401,I001  (before dolfinx: see ureterfsi/__init__.py)
import numpy as np
import xarray as xr

from . import tags
from .checked_io import MESH_SIDECAR, Contract, open_netcdf, read_json
from .config import check_stability, deep_merge, schema_defaults
from .metadata import write_netcdf
from .provenance import provenance_attrs

log = logging.getLogger("ureterfsi.stability")

SYMMETRY = "axisymmetric"

# axis -> (units, long name, scale of the stability-map axis)
# (symlog: logarithmic with a linear part around 0, for a list that includes 0)
AXES = {
    "time_step": ("s", "time step", "log"),
    "mesh_level": ("1", "r-z mesh level", "log"),
    "bulk_ratio": ("1", "near-incompressibility kappa / (C10 + C01) of the wall", "log"),
    "density_ratio": ("1", "density ratio wall / urine", "log"),
    "load_amplitude": ("Pa", "peak traction of the peristaltic pulse", "symlog"),
    "wave_speed": ("m s-1", "speed of the peristaltic pulse", "log"),
    "wave_width": ("m", "width of the peristaltic pulse", "log"),
    "viscosity": ("Pa s", "dynamic viscosity of the urine", "log"),
    "hole_elements": ("1", "elements across a side hole (3D, one-way)", "log"),
}
# parameter variable of the combined dataset behind each axis
AXIS_PARAMETER = {"time_step": "time_step", "mesh_level": "cells", "bulk_ratio": "bulk_ratio",
                  "density_ratio": "density_ratio", "load_amplitude": "peak_traction",
                  "wave_speed": "wave_speed", "wave_width": "wave_width", "viscosity": "dynamic_viscosity",
                  "hole_elements": "hole_elements_measured"}
# what the rows of each field of the monolithic system are
ROWS = {"velocity": "momentum (velocity)", "displacement": "kinematic / mesh-motion (displacement)",
        "pressure": "continuity (fluid pressure)", "solid_pressure": "volumetric constraint (solid pressure)"}
LIMITS = ("none", "newton", "nan", "ale_inversion", "energy", "volume", "wall_time", "exception")
SCENES = {"rz": "r-z (axisymmetric), fully coupled monolithic ALE, P2-P2-P1-P0, BDF2",
          "holes": "3D, one-way: r-z wall -> urine alone on the fluid submesh (ALE P2-P1, segregated mesh "
                   "motion, BDF2), stent rigid"}


class StabilityLimit(RuntimeError):
    """A case reached one of the limits of the stability study (raised by the observer)."""

    def __init__(self, limit: str, message: str, time: float = math.nan, where=(math.nan, math.nan),
                 what: str = "", value: float = math.nan):
        super().__init__(message)
        self.limit, self.time, self.where, self.what, self.value = limit, time, tuple(where), what, value


# -------------------------------------------------------------------------------------------- cases
@dataclass(frozen=True)
class Case:
    """One point of the matrix: `axis` (a key of AXES, or "baseline") set to `value` (SI units)."""
    axis: str
    value: float | str | None = None

    @property
    def name(self) -> str:
        if self.axis == "baseline":
            return "baseline"
        return f"{self.axis}_{format_value(self.value)}"


def format_value(value) -> str:
    """Short file-name-safe label of a value: 0.001, 1e5, 2e-4, medium."""
    if isinstance(value, str):
        return value
    text = f"{float(value):.3g}"
    return re.sub(r"e([+-])0*(\d)", lambda m: "e" + ("-" if m.group(1) == "-" else "") + m.group(2), text)


def settings(cfg: dict) -> dict:
    """The `stability` section of cfg with the schema's defaults filled in (no section: the baseline alone)."""
    return deep_merge({"axes": {}} | schema_defaults("stability"), cfg.get("stability") or {})


def cases(cfg: dict) -> list[Case]:
    """Every case of the matrix: the baseline first, then each axis's values in config order."""
    st = settings(cfg)
    out = [Case("baseline")]
    for axis, values in st["axes"].items():
        out += [Case(axis, v if axis == "mesh_level" else float(v)) for v in values]
    return out


def case_by_name(cfg: dict, name: str) -> Case:
    for c in cases(cfg):
        if c.name == name:
            return c
    raise KeyError(f"no stability case {name!r}; cases: {[c.name for c in cases(cfg)]}")


def case_setup(cfg: dict, case: Case) -> dict:
    """Configuration of one case: {"cfg": modified copy, "dt", "level", "end", "parameters": {...}}.

    A `stability` section that ureterfsi.config.check_stability refuses raises its ConfigError."""
    st = settings(cfg)
    c = deepcopy(cfg)
    dt, level, end = float(cfg["time"]["dt"]), str(st["level"]), float(st["end"])
    scene, model, symmetry, hole_elements = "rz", str(st["model"]), SYMMETRY, math.nan
    u, f, p = c["ureter"], c["fluid"], c["peristalsis"]
    if case.axis == "time_step":
        dt = float(case.value)
    elif case.axis == "mesh_level":
        level = str(case.value)
    elif case.axis == "bulk_ratio":
        u["bulk_modulus"] = float(case.value) * (u["c10"] + u["c01"])
    elif case.axis == "density_ratio":
        u["density"] = float(case.value) * f["density"]
    elif case.axis == "load_amplitude":
        p["peak_traction"] = float(case.value)
    elif case.axis == "wave_speed":
        # the pulse travels the same distance as in the baseline
        end *= cfg["peristalsis"]["speed"] / float(case.value)
        p["speed"] = float(case.value)
    elif case.axis == "wave_width":
        p["width"] = float(case.value)
    elif case.axis == "viscosity":
        f["dynamic_viscosity"] = float(case.value)
    elif case.axis == "hole_elements":
        scene, model, symmetry = "holes", str(st["holes"]["model"]), str(st["holes"]["symmetry"])
        hole_elements = float(case.value)
        if level in cfg["mesh"]["levels"]:
            f_level = float(cfg["mesh"]["levels"][level]["size_factor"])
            sizes, g = c["mesh"]["sizes"], cfg["geometry"]
            sizes["hole"] = g["hole_diameter"] / (hole_elements * f_level)
            # the stent-wall size caps the hole size (min of the size fields): a hole coarser than it
            # coarsens the stent wall too (n = 1: one element through the 0.5 mm wall)
            sizes["stent_wall"] = max(sizes["stent_wall"], sizes["hole"])
            # below the study's minima on purpose: the case's configuration stays consistent with its
            # mesh.resolution_minima (ureterfsi.config.check_resolution)
            minima = c["mesh"]["resolution_minima"]
            minima["hole"] = min(minima["hole"], hole_elements)
            minima["stent_wall"] = min(minima["stent_wall"],
                                       g["stent_wall_thickness"] / (sizes["stent_wall"] * f_level))
    elif case.axis != "baseline":
        raise ValueError(f"unknown stability axis {case.axis!r}; one of baseline, {', '.join(AXES)}")
    check_stability(cfg)
    params = {"time_step": dt, "mesh_level": level, "bulk_ratio": u["bulk_modulus"] / (u["c10"] + u["c01"]),
              "density_ratio": u["density"] / f["density"], "peak_traction": p["peak_traction"],
              "wave_speed": p["speed"], "wave_width": p["width"], "dynamic_viscosity": f["dynamic_viscosity"],
              "hole_elements": hole_elements, "end_time": end}
    # the baseline of each scene: the r-z baseline case, and the hole case on the study's own mesh
    default_elements = (cfg["geometry"]["hole_diameter"]
                        / (cfg["mesh"]["sizes"]["hole"] * cfg["mesh"]["levels"][level]["size_factor"]))
    params["is_baseline"] = int(case.axis == "baseline" or (
        scene == "holes" and abs(hole_elements - default_elements) <= 1e-6 * default_elements))
    return {"cfg": c, "dt": dt, "level": level, "end": end, "model": model, "scene": scene,
            "symmetry": symmetry, "parameters": params}


# ----------------------------------------------------------------------------------------- observer
class _HalvingCounter(logging.Handler):
    """Counts the engine's "retrying with dt/2" warnings (one per step halving) during a case."""

    def __init__(self):
        super().__init__(logging.WARNING)
        self.times, self.messages = [], []

    def emit(self, record):
        msg = record.getMessage()
        if "retrying with dt/2" in msg:
            m = re.search(r" t=([-+0-9.eE]+) s", msg)
            self.times.append(float(m.group(1)) if m else math.nan)
            self.messages.append(msg)


class StabilityObserver:
    """Energy, volume balance, solver effort and limits of one case, after every accepted step.

    (An engine Observer: `observe(problem, step)`; raises StabilityLimit at the energy, NaN and
    wall-time limits, which stops the run.)"""

    def __init__(self, pb, cfg: dict, st: dict, wall0: float | None = None):
        import ufl
        from dolfinx import fem

        from dolfinx.fem import petsc as fem_petsc

        from .fsi import physics
        from .fsi.materials import LinearElastic, MooneyRivlin

        self.pb, self.st = pb, st
        self.comm = pb.comm
        self.wall0 = _time.perf_counter() if wall0 is None else wall0
        ops, dx, ds = pb.ops, pb.dx, pb.ds
        X = pb.split()
        v, u = X["velocity"], X["displacement"]
        V = ops.vec(v)
        F = physics.deformation_gradient(ops, u)
        J = ufl.det(F)
        n_da = J * ufl.inv(F).T * ops.normal()
        rel = V - ops.vec(pb.split(pb.x_dot)["displacement"])   # v - w, w the mesh velocity
        w = ops.weight
        sc = pb.scene
        fl = sc.fluid
        forms = {
            "kinetic_energy_fluid": 0.5 * fl.material.density * ufl.dot(V, V) * J * w * dx(tuple(fl.tags)),
            "fluid_volume": J * w * dx(tuple(fl.tags)),
            "outlet_flux": ufl.dot(rel, n_da) * w * ds(tags.OUTLET),
            "inlet_flux": -ufl.dot(rel, n_da) * w * ds(tags.INLET),
        }
        ke_s, el = 0, 0   # stay 0 (recorded as 0.0) in a fluid-alone scene
        for solid in sc.solids:
            mat, dxs = solid.material, dx(tuple(solid.tags))
            ke_s += 0.5 * mat.density * ufl.dot(V, V) * w * dxs
            if isinstance(mat, MooneyRivlin):
                el += (physics.mooney_rivlin_isochoric_energy(ops, mat, F)
                       + 0.5 * mat.bulk_modulus * (J - 1.0) ** 2) * w * dxs
            elif isinstance(mat, LinearElastic):
                el += 0.5 * ufl.inner(physics.elastic_first_piola(ops, mat, u), ops.grad(u)) * w * dxs
        X_ref = ufl.SpatialCoordinate(pb.mesh)
        p_load = 0
        for load in sc.loads:
            p_load += ufl.dot(load.traction(X_ref, pb.t, ops.normal()), V) * w * ds(tuple(load.tags))
        p_open = 0
        for ob in sc.open_boundaries:
            p_open += -ob.normal_stress * ufl.dot(n_da, V) * w * ds(tuple(ob.tags))
        forms.update(kinetic_energy_solid=ke_s, elastic_energy=el, load_power=p_load, open_boundary_power=p_open)
        self.forms = {k: fem.form(f) for k, f in forms.items() if not isinstance(f, (int, float))}
        self.absent = [k for k, f in forms.items() if isinstance(f, (int, float))]

        # power of the prescribed motion: the consistent reaction R (residual without boundary conditions)
        # times the velocity, over the owned velocity dofs of the mixed space
        self._reaction = fem_petsc.create_vector(pb.residual_form)
        vdofs = np.asarray(pb.sub("velocity").collapse()[1])
        n_owned = pb.W.dofmap.index_map.size_local * pb.W.dofmap.index_map_bs
        self._velocity_dofs = vdofs[vdofs < n_owned]

        # minimum ALE Jacobian and where (DG1 at the vertices of the fluid cells; limit 1 + du_r/dr on the axis)
        Q = fem.FunctionSpace(pb.mesh, ("DG", 1))
        if ops.axisymmetric:
            g = ufl.grad(u)
            F_axis = ufl.as_tensor([[F[0, 0], 0.0, F[0, 2]], [0.0, 1.0 + g[0, 0], 0.0], [F[2, 0], 0.0, F[2, 2]]])
            J = ufl.conditional(ufl.gt(abs(ops.r), 1e-300), J, ufl.det(F_axis))
        self._jac = fem.Function(Q)
        self._jac_expr = fem.Expression(J, Q.element.interpolation_points())
        n_local = pb.mesh.topology.index_map(pb.mesh.topology.dim).size_local
        ct = sc.cell_tags
        cells = np.unique(np.concatenate([ct.find(t) for t in fl.tags])).astype(np.int32)
        cells = cells[cells < n_local]
        self._jac_dofs = np.unique(Q.dofmap.list.array.reshape(-1, Q.dofmap.dof_layout.num_dofs)[cells].ravel())
        self._jac_xyz = Q.tabulate_dof_coordinates()
        self.axisymmetric = ops.axisymmetric
        # dof coordinates of every field of the mixed space (diagnosis of the place)
        self._fields = []
        for name in pb.field_names:
            Vc, dofs = pb.sub(name).collapse()
            self._fields.append((name, np.asarray(dofs), Vc.dofmap.index_map_bs, Vc.tabulate_dof_coordinates()))
        self._disp_dofs = self._fields[pb.index["displacement"]][1]
        self.series = {k: [] for k in SERIES}
        self._vb = []          # BDF-integrated volume
        self._work = 0.0

    # -- helpers ------------------------------------------------------------------------------------
    def _assemble(self, name) -> float:
        from dolfinx import fem
        from mpi4py import MPI

        return float(self.comm.allreduce(fem.assemble_scalar(self.forms[name]), op=MPI.SUM))

    def _gather_min(self, value, xyz):
        """(value, xyz) of the rank holding the global minimum."""
        return min(self.comm.allgather((value, tuple(xyz))), key=lambda t: t[0])

    def _rz(self, xyz):
        """Reference (r, z) of a dof coordinate: (x, y) in r-z, (sqrt(x^2 + y^2), z) in 3D."""
        return (xyz[0], xyz[1]) if self.axisymmetric else (math.hypot(xyz[0], xyz[1]), xyz[2])

    def prescribed_power(self) -> float:
        """sum_i R_i v_i: the power the Dirichlet conditions put into the system (see the module doc)."""
        from mpi4py import MPI

        r = self._reaction
        self.pb.assemble_reaction(r)
        d = self._velocity_dofs
        local = float(np.dot(r.array_r[d], self.pb.x.x.array[d]))
        return float(self.comm.allreduce(local, op=MPI.SUM))

    def min_jacobian(self):
        """(min ALE Jacobian over the fluid vertices, its reference (r, z))."""
        self._jac.interpolate(self._jac_expr)
        vals = self._jac.x.array[self._jac_dofs]
        if vals.size:
            bad = ~np.isfinite(vals)
            i = int(np.argmax(bad)) if bad.any() else int(np.argmin(vals))
            local = (float(vals[i]) if not bad.any() else -math.inf, self._rz(self._jac_xyz[self._jac_dofs[i]]))
        else:
            local = (math.inf, (math.nan, math.nan))
        return self._gather_min(*local)

    def fastest_node(self):
        """(max |v|, its reference (r, z)) over the whole mesh (NaN entries first)."""
        name, dofs, bs, xyz = self._fields[self.pb.index["velocity"]]
        vals = self.pb.x.x.array[dofs].reshape(-1, bs)
        speed = np.sqrt((vals ** 2).sum(axis=1))
        bad = ~np.isfinite(speed)
        i = int(np.argmax(bad)) if bad.any() else int(np.argmax(speed)) if speed.size else 0
        local = (-math.inf if bad.any() else (-float(speed[i]) if speed.size else math.inf),
                 self._rz(xyz[i]) if speed.size else (math.nan, math.nan))
        val, where = self._gather_min(*local)
        return -val, where

    def largest_residual(self):
        """(field, |R| entry, reference (r, z)) of the largest (or first non-finite) entry of the last
        assembled Newton residual, e.g. the last iterate of a failed step."""
        b = self.pb.b.array
        best = (-math.inf, "", (math.nan, math.nan))
        for name, dofs, bs, xyz in self._fields:
            idx = np.flatnonzero(dofs < b.size)      # owned entries of the residual vector
            vals = np.abs(b[dofs[idx]])
            if not vals.size:
                continue
            bad = ~np.isfinite(vals)
            j = int(np.argmax(bad)) if bad.any() else int(np.argmax(vals))
            val = math.inf if bad.any() else float(vals[j])
            if val > best[0]:
                best = (val, ROWS.get(name, name), tuple(self._rz(xyz[idx[j] // bs])))
        val, name, where = max(self.comm.allgather(best), key=lambda t: t[0])
        return name, val, where

    # -- the observer -------------------------------------------------------------------------------
    def observe(self, pb, step: int) -> None:
        from mpi4py import MPI

        s = self.series
        val = {k: self._assemble(k) for k in self.forms} | {k: 0.0 for k in self.absent}
        val["prescribed_power"] = self.prescribed_power()
        dt = float(pb.dt.value) if step else 0.0
        b0, b1, b2 = (float(c.value) for c in pb.bdf) if step else (1.0, 0.0, 0.0)
        q = val["outlet_flux"] - val["inlet_flux"]
        if step == 0:
            self._vb = [val["fluid_volume"]]
            self.initial_energy = val["kinetic_energy_fluid"] + val["kinetic_energy_solid"] + val["elastic_energy"]
        else:
            vb2 = self._vb[-2] if len(self._vb) >= 2 else 0.0
            self._vb.append((-dt * q - b1 * self._vb[-1] - b2 * vb2) / b0)
            self._work += dt * (abs(val["load_power"]) + abs(val["open_boundary_power"])
                                + abs(val["prescribed_power"]))
        ke = val["kinetic_energy_fluid"] + val["kinetic_energy_solid"]
        jmin, _ = self.min_jacobian()
        umax = self.comm.allreduce(float(np.nanmax(np.abs(pb.x.x.array[self._disp_dofs]), initial=0.0)),
                                   op=MPI.MAX)
        bound = self.initial_energy + self._work
        vmax, _ = self.fastest_node()
        row = {"time": pb.time, "dt": dt, "kinetic_energy": ke, "energy_bound": bound, "max_speed": vmax,
               "external_work": self._work, "volume_from_flux": self._vb[-1],
               "min_ale_jacobian": jmin, "max_displacement": umax, **val}
        for k in SERIES:
            if k in row:
                s[k].append(row[k])
        t = pb.time
        bad = [k for k, x in row.items() if not math.isfinite(x)]
        if bad:
            vmax, where = self.fastest_node()
            raise StabilityLimit("nan", f"non-finite {', '.join(bad)} at t = {t:.6g} s (step {step})", t, where,
                                 "fastest (or first non-finite) node")
        if ke > self.st["energy_safety"] * bound:
            vmax, where = self.fastest_node()
            raise StabilityLimit(
                "energy", f"kinetic energy {ke:.3e} J exceeds {self.st['energy_safety']:g} x the bound "
                f"E(0) + E_el(0) + W(t) = {bound:.3e} J at t = {t:.6g} s (step {step})", t, where,
                f"fastest node, |v| = {vmax:.3e} m/s, at")
        elapsed = _time.perf_counter() - self.wall0
        if elapsed > self.st["max_wall_time"]:
            raise StabilityLimit("wall_time", f"wall-time budget stability.max_wall_time = "
                                 f"{self.st['max_wall_time']:g} s exceeded at t = {t:.6g} s (step {step})", t,
                                 (math.nan, math.nan))


SERIES = ("time", "dt", "kinetic_energy", "kinetic_energy_fluid", "kinetic_energy_solid", "elastic_energy",
          "energy_bound", "load_power", "open_boundary_power", "prescribed_power", "external_work", "fluid_volume",
          "volume_from_flux", "outlet_flux", "inlet_flux", "min_ale_jacobian", "max_displacement", "max_speed")

# CF metadata: name -> (units, long_name)
CF = {
    "time": ("s", "time"),
    "step": ("1", "index of the recorded state (0: initial state, then every accepted time step)"),
    "dt": ("s", "length of the accepted time step (0 for the initial state)"),
    "kinetic_energy": ("J", "kinetic energy of urine and wall: int_fluid 1/2 rho |v|^2 dx + int_wall 1/2 rho0 |v|^2 dX"),
    "kinetic_energy_fluid": ("J", "kinetic energy of the urine, int 1/2 rho |v|^2 J dX (whole tube)"),
    "kinetic_energy_solid": ("J", "kinetic energy of the ureter wall, int 1/2 rho0 |v|^2 dX (whole tube)"),
    "elastic_energy": ("J", "strain energy of the ureter wall, int W(F) dX (Mooney-Rivlin, >= 0)"),
    "energy_bound": ("J", "E(0) + E_el(0) + W(t): the kinetic energy a dissipative system cannot exceed"),
    "load_power": ("W", "power of the peristaltic load on the wall, int t . v dA"),
    "open_boundary_power": ("W", "power of the prescribed normal stress on the open ends, -p_ref int v . n da"),
    "prescribed_power": ("W", "power of the prescribed (Dirichlet) motion, sum_i R_i v_i over the velocity dofs "
                         "(R: residual without boundary conditions)"),
    "external_work": ("J", "W(t) = int_0^t |load power| + |open-boundary power| + |prescribed power| dt "
                      "(rectangle rule)"),
    "fluid_volume": ("m3", "fluid volume V(t) = int_fluid J dX (whole tube)"),
    "volume_from_flux": ("m3", "V(0) - int_0^t (Q_out - Q_in) dt, the flux integrated with the BDF weights of each step"),
    "volume_balance_error": ("m3", "|V(t) - V(0) + int_0^t (Q_out - Q_in) dt|"),
    "outlet_flux": ("m3 s-1", "volumetric flow rate through the outlet, positive out of the ureter"),
    "inlet_flux": ("m3 s-1", "volumetric flow rate through the inlet, positive into the ureter"),
    "min_ale_jacobian": ("1", "minimum Jacobian of the ALE map over the fluid vertices (<= 0: inverted)"),
    "max_displacement": ("m", "largest nodal displacement component over wall and ALE mesh"),
    "max_speed": ("m s-1", "largest nodal speed |v| (a local instability shows here before it shows in the "
                  "kinetic energy)"),
    "newton_iterations": ("1", "Newton iterations of the accepted step"),
    "step_wall_time": ("s", "wall-clock time of the accepted step (its last attempt)"),
    "halving_time": ("s", "end time of each failed step attempt (retried with dt/2, or the last of a failed step)"),
    # per case
    "case": ("1", "name of the stability case (<axis>_<value>, or baseline)"),
    "axis": ("1", "the varied quantity (stability.axes key; baseline: none)"),
    "value_label": ("1", "value of the varied quantity, as in the configuration"),
    "outcome": ("1", "stable (ran to the end, energy bounded, volume conserved) or failed"),
    "limit": ("1", "limit that ended a failed case: " + ", ".join(LIMITS)),
    "diagnosis": ("1", "what failed, when and where (empty if stable)"),
    "failure_time": ("s", "time at which the limit was hit (NaN if stable)"),
    "failure_r": ("m", "reference radial coordinate of the place of the failure (NaN if none)"),
    "failure_z": ("m", "reference axial coordinate of the place of the failure (NaN if none)"),
    "pulse_centre_at_failure": ("m", "axial position of the pulse centre at the failure time"),
    "time_step": ("s", "nominal time step"),
    "mesh_level": ("1", "mesh level (config mesh.levels)"),
    "scene": ("1", "rz: r-z model, fully coupled; holes: 3D stented model, one-way (the urine alone)"),
    "cells": ("1", "number of cells of the mesh (3D: every subdomain of the symmetry sector)"),
    "dofs": ("1", "number of unknowns of the monolithic system (3D one-way: of the urine problem)"),
    "hole_elements": ("1", "elements across a side-hole diameter, hole_diameter / mesh size (NaN: no holes)"),
    "hole_elements_measured": ("1", "hole diameter / mean edge length of the hole-wall triangles of the mesh "
                               "(NaN: no holes)"),
    "is_baseline": ("1", "1 for the baseline of the case's scene (r-z: baseline; 3D: the study's own mesh)"),
    "hole_channels_found": ("1", "side-hole channels found in the mesh (ureterfsi.mesh.hole_channels)"),
    "mesh_min_quality": ("1", "smallest signed inverse condition number (gmsh minSICN) of the mesh cells"),
    "bulk_ratio": ("1", "kappa / (C10 + C01) of the ureter wall"),
    "density_ratio": ("1", "ureter wall density / urine density"),
    "peak_traction": ("Pa", "peak traction of the peristaltic pulse"),
    "wave_speed": ("m s-1", "speed of the peristaltic pulse"),
    "wave_width": ("m", "width of the peristaltic pulse (in peristalsis.width_measure)"),
    "dynamic_viscosity": ("Pa s", "dynamic viscosity of the urine"),
    "end_time": ("s", "time the case was to reach"),
    "reached_time": ("s", "last accepted time"),
    "steps": ("1", "number of accepted time steps"),
    "max_kinetic_energy": ("J", "maximum over time of the kinetic energy"),
    "max_energy_ratio": ("1", "maximum over time of kinetic energy / energy_bound (limit: stability.energy_safety)"),
    "displaced_volume": ("m3", "volume the wave displaces, max over time of |V(t) - V(0)|"),
    "volume_error": ("1", "maximum over time of the volume balance error relative to the displaced volume"),
    "min_jacobian": ("1", "minimum over time of the minimum ALE Jacobian"),
    "max_wall_displacement": ("m", "maximum over time of the maximum nodal displacement"),
    "peak_speed": ("m s-1", "maximum over time of the largest nodal speed"),
    "total_newton_iterations": ("1", "Newton iterations of all accepted steps"),
    "mean_newton_iterations": ("1", "mean Newton iterations per accepted step"),
    "max_newton_iterations": ("1", "largest number of Newton iterations of an accepted step"),
    "step_halvings": ("1", "number of failed step attempts retried with dt/2 (engine retries)"),
    "factorisations": ("1", "LU factorisations of the Jacobian"),
    "wall_time": ("s", "wall-clock time of the case (set-up, initial state and time steps)"),
    "wall_time_per_step": ("s", "mean wall-clock time per accepted step"),
}


def _annotate(ds: xr.Dataset) -> xr.Dataset:
    for name in list(ds.variables):
        units, long_name = CF[str(name)]
        ds[name].attrs.update(units=units, long_name=long_name)
    return ds


# ---------------------------------------------------------------------------------------- one case
def _failure_from_engine(err, obs, pb, attempts) -> StabilityLimit:
    """Turn an engine failure into a StabilityLimit with the place. An inverted mesh is the state of the
    last step (time: pb.time); a failed step is not accepted (time: the end of its last attempt)."""
    msg = str(err)
    if "ALE mesh inverted" in msg:
        jmin, where = obs.min_jacobian()
        return StabilityLimit("ale_inversion", msg, pb.time, where,
                              f"smallest ALE Jacobian {jmin:.3e} at the fluid vertex", jmin)
    t = attempts[-1] if attempts else pb.time
    name, val, where = obs.largest_residual()
    limit = "nan" if ("non-finite" in msg or not math.isfinite(val)) else "newton"
    return StabilityLimit(limit, msg, t, where,
                          f"largest entry {val:.3e} of the last Newton residual, in the {name} rows, at", val)


def _nanmin(values) -> float:
    v = np.asarray(values, dtype=float)
    v = v[~np.isnan(v)]
    return float(v.min()) if v.size else math.nan


def _place(where) -> str:
    r, z = where
    if not (math.isfinite(r) and math.isfinite(z)):
        return "an unknown place"
    return f"(r, z) = ({r * 1e3:.2f}, {z * 1e3:.2f}) mm"


def _region(where, geom, stented: bool = False) -> str:
    r, _ = where
    if not math.isfinite(r):
        return ""
    R = geom.ureter_inner_radius
    if r > R * (1 + 1e-9):
        return "wall"
    if r >= R * (1 - 1e-9):
        return "urine-wall interface"
    if not stented:
        return "urine"
    return ("urine in the stent lumen" if r < geom.stent_inner_radius else "urine in a side hole"
            if r <= geom.stent_outer_radius else "urine in the annulus")


def run_case(cfg: dict, case: Case, mesh_path=None, end: float | None = None) -> xr.Dataset:
    """Run one case of the matrix and return its dataset (dims `step` and `halving`; scalars per case).

    mesh_path: the mesh of the case (r-z at the case's level; built in a temporary directory if None, as
    the hole_elements cases always are: their mesh sizes are the case's);
    end: override of the simulated time (short CI runs). Never raises for a failing case: the failure
    is the outcome, with its diagnosis.
    """
    from mpi4py import MPI

    from .fsi import MonolithicFSI, SolveFailure, TimeIntegrator, TimeSettings
    from .fsi.problem import NewtonDivergence
    from .geometry import UreterGeometry
    from .mesh import build_mesh, load_mesh
    from .oneway import fluid_problem, wall_history
    from .scenes.ureter import pulse_centre, ureter_scene
    from .study import solver_options

    wall0 = _time.perf_counter()
    st = settings(cfg)
    setup = case_setup(cfg, case)
    ccfg, params = setup["cfg"], dict(setup["parameters"])
    if end is not None:
        params["end_time"] = float(end)
    comm = MPI.COMM_WORLD
    geom = UreterGeometry.from_config(cfg)
    counter = _HalvingCounter()
    engine_log = logging.getLogger("ureterfsi.fsi")
    engine_log.addHandler(counter)
    pb = obs = integrator = None
    failure: StabilityLimit | None = None
    engine_gave_up = False
    cells = dofs = 0
    sidecar = {}
    holes = setup["scene"] == "holes"
    try:
        with tempfile.TemporaryDirectory() as tmp:
            if mesh_path is None or holes:
                mesh_path = Path(tmp) / "mesh.msh"
                if comm.rank == 0:
                    build_mesh(ccfg, setup["model"], setup["level"], setup["symmetry"], mesh_path,
                               Path(tmp) / "mesh.json")
                comm.Barrier()
            mesh, ct, ft = load_mesh(mesh_path, comm)
            side = Path(mesh_path).with_suffix(".json")
            if side.exists():
                sidecar = read_json(side, MESH_SIDECAR)
        cells = mesh.topology.index_map(mesh.topology.dim).size_global
        if holes:
            history = wall_history(ccfg, params["end_time"], setup["dt"])
            pb, _ = fluid_problem(ccfg, mesh, ct, ft, history, axisymmetric=False)
        else:
            pb = MonolithicFSI(ureter_scene(ccfg, mesh, ct, ft, axisymmetric=True,
                                            peristalsis=ccfg["peristalsis"]), solver_options(ccfg))
        dofs = pb.W.dofmap.index_map.size_global * pb.W.dofmap.index_map_bs
        obs = StabilityObserver(pb, ccfg, st, wall0)
        log.info("case %s: %d cells, %d dofs, dt %g s, end %g s", case.name, cells, dofs, setup["dt"],
                 params["end_time"])
        integrator = TimeIntegrator(pb, TimeSettings(
            end=params["end_time"], dt=setup["dt"], max_halvings=ccfg["solver"]["max_step_halvings"],
            min_ale_jacobian=st["min_ale_jacobian"]), [obs])
        try:
            pb.fill("pressure", ccfg["fluid"]["reference_pressure"])
            pb.solve_steady()
        except NewtonDivergence as err:
            raise SolveFailure(f"initial state (steady, fluid at rest) failed: {err}") from err
        integrator.run()
    except StabilityLimit as err:
        failure = err
    except SolveFailure as err:
        engine_gave_up = "halvings" in str(err)
        failure = (_failure_from_engine(err, obs, pb, counter.times) if obs is not None
                   else StabilityLimit("newton", str(err)))
    except Exception as err:  # noqa: BLE001 - a case must never crash the matrix
        log.exception("case %s raised", case.name)
        t = pb.time if pb is not None else math.nan
        failure = StabilityLimit("exception", f"{type(err).__name__}: {err}", t)
    finally:
        engine_log.removeHandler(counter)
    wall = _time.perf_counter() - wall0

    series = obs.series if obs is not None else {k: [] for k in SERIES}
    records = integrator.records if integrator is not None else []
    n = len(series["time"])
    data = {k: ("step", np.asarray(series[k], dtype=float)) for k in SERIES if k != "time"}
    vol, vb = np.asarray(series["fluid_volume"], float), np.asarray(series["volume_from_flux"], float)
    data["volume_balance_error"] = ("step", np.abs(vol - vb))
    its = np.zeros(n)
    swall = np.zeros(n)
    for r in records[: max(n - 1, 0)]:
        its[r.step], swall[r.step] = r.newton_iterations, r.wall_time
    data["newton_iterations"] = ("step", its)
    data["step_wall_time"] = ("step", swall)
    data["halving_time"] = ("halving", np.asarray(counter.times, dtype=float))

    displaced = float(np.nanmax(np.abs(vol - vol[0]))) if n else math.nan
    # a case without a wave (zero load) displaces nothing: its balance error is then measured against
    # the displacement the design rule asks of the pulse (volume of a Gaussian bulge of the design height)
    sigma = ccfg["peristalsis"]["width"] / (2 * math.sqrt(2 * math.log(2))) \
        if ccfg["peristalsis"]["width_measure"] == "fwhm" else ccfg["peristalsis"]["width"]
    nominal = 2 * math.pi * geom.ureter_inner_radius * cfg["ureter"]["design_wall_displacement"] \
        * sigma * math.sqrt(2 * math.pi)
    ref = displaced if displaced > 1e-6 * nominal else nominal
    verr = float(np.nanmax(np.abs(vol - vb)) / ref) if n else math.nan
    ke = np.asarray(series["kinetic_energy"], float)
    bound = np.asarray(series["energy_bound"], float)
    if failure is None and n and verr > st["volume_tolerance"]:
        k = int(np.nanargmax(np.abs(vol - vb)))
        failure = StabilityLimit("volume", f"volume balance error {verr:.3e} of the displaced volume exceeds "
                                 f"stability.volume_tolerance = {st['volume_tolerance']:g} (largest at t = "
                                 f"{series['time'][k]:.6g} s)", series["time"][k])
    if failure is None and n and series["time"][-1] < params["end_time"] - 1e-9 * setup["dt"]:
        failure = StabilityLimit("exception", f"run stopped at t = {series['time'][-1]:.6g} s before the end")

    ttime = failure.time if failure is not None else math.nan
    zc = pulse_centre(ccfg["peristalsis"], ttime) if math.isfinite(ttime) else math.nan
    diagnosis = ""
    if failure is not None:
        where = failure.where
        region = _region(where, geom, stented=holes)
        diagnosis = f"{failure.limit}: {failure}"
        if math.isfinite(where[0]):
            what = failure.what or "place"
            diagnosis += f" [where: {what} {_place(where)}, {region}; pulse centre at z = {zc * 1e3:.2f} mm]"
        elif math.isfinite(zc):
            diagnosis += f" [pulse centre at z = {zc * 1e3:.2f} mm]"
    scalars = {
        "axis": case.axis if case.axis != "baseline" else "baseline",
        "value_label": "" if case.value is None else format_value(case.value),
        "outcome": "stable" if failure is None else "failed",
        "limit": "none" if failure is None else failure.limit,
        "diagnosis": diagnosis,
        "failure_time": ttime,
        "failure_r": failure.where[0] if failure is not None else math.nan,
        "failure_z": failure.where[1] if failure is not None else math.nan,
        "pulse_centre_at_failure": zc,
        "scene": setup["scene"],
        "time_step": params["time_step"], "mesh_level": params["mesh_level"], "cells": cells, "dofs": dofs,
        "hole_elements": params["hole_elements"], "is_baseline": params["is_baseline"],
        "hole_elements_measured": float(sidecar.get("hole_elements_across", math.nan)),
        "hole_channels_found": int(sidecar.get("hole_channels_found", 0)),
        "mesh_min_quality": float(sidecar.get("quality_minSICN", {}).get("min", math.nan)),
        "bulk_ratio": params["bulk_ratio"], "density_ratio": params["density_ratio"],
        "peak_traction": params["peak_traction"], "wave_speed": params["wave_speed"],
        "wave_width": params["wave_width"], "dynamic_viscosity": params["dynamic_viscosity"],
        "end_time": params["end_time"],
        "reached_time": series["time"][-1] if n else math.nan,
        "steps": max(n - 1, 0),
        "max_kinetic_energy": float(np.nanmax(ke)) if n else math.nan,
        # from the first step on (at t = 0 the bound is E(0) itself)
        "max_energy_ratio": float(np.nanmax(ke[1:] / np.where(bound[1:] > 0, bound[1:], np.nan))) if n > 1
        else math.nan,
        "displaced_volume": displaced,
        "volume_error": verr,
        # an inverted mesh is not an accepted state (not in the series): its Jacobian is the failure's
        "min_jacobian": _nanmin(list(series["min_ale_jacobian"]) + (
            [failure.value] if failure is not None and failure.limit == "ale_inversion" else [])),
        "max_wall_displacement": float(np.nanmax(series["max_displacement"])) if n else math.nan,
        "peak_speed": float(np.nanmax(series["max_speed"])) if n else math.nan,
        "total_newton_iterations": int(its.sum()),
        "mean_newton_iterations": float(its[1:].mean()) if n > 1 else math.nan,
        "max_newton_iterations": int(its.max()) if n else 0,
        # every failed attempt is logged "retrying with dt/2", also the last one of a step the engine gives up on
        "step_halvings": len(counter.times) - (1 if engine_gave_up else 0),
        "factorisations": pb.counters["factorisations"] if pb is not None else 0,
        "wall_time": wall,
        "wall_time_per_step": float(swall[1:].mean()) if n > 1 else math.nan,
    }
    ds = xr.Dataset({k: ((), v) for k, v in scalars.items()} | data,
                    coords={"step": np.arange(n), "time": ("step", np.asarray(series["time"], float))})
    ds = ds.assign_coords(case=case.name)
    _annotate(ds)
    ds.attrs.update(provenance_attrs(ccfg, title=f"ureterfsi stability case {case.name}", case=case.name,
                                     model=setup["model"], symmetry=setup["symmetry"], mesh_level=setup["level"],
                                     energy_safety=st["energy_safety"], volume_tolerance=st["volume_tolerance"],
                                     min_ale_jacobian_limit=st["min_ale_jacobian"],
                                     solver=f"{SCENES[setup['scene']]}; Newton + "
                                            f"{ccfg['solver']['linear_solver']}",
                                     processes=comm.size))
    log.info("case %s: %s %s (%.1f s)", case.name, scalars["outcome"], diagnosis, wall)
    return ds


# what combine reads in a per-case file (run_case)
CASE_FILE = Contract("stability case file", attrs=("case",), variables=("case", "step", "time", "outcome"))


def write_case(ds: xr.Dataset, path) -> None:
    write_netcdf(ds, path)


# ----------------------------------------------------------------------------------------- combine
PER_STEP = tuple(k for k in SERIES if k != "time") + ("volume_balance_error", "newton_iterations",
                                                       "step_wall_time")


def combine(items, cfg: dict | None = None) -> xr.Dataset:
    """Per-case datasets (or their paths) -> one dataset with dimension `case` (in the given order):
    every per-case scalar, and the time series padded with NaN along `step`."""
    runs = []
    for it in items:
        if isinstance(it, xr.Dataset):
            runs.append(it)
        else:
            runs.append(open_netcdf(it, CASE_FILE))
    if not runs:
        raise ValueError("no stability case to combine")
    names = [str(r["case"].values) for r in runs]
    nstep = max(r.sizes.get("step", 0) for r in runs)
    nhalv = max([r.sizes.get("halving", 0) for r in runs] + [0])
    scalar_names = [k for k, v in runs[0].data_vars.items() if v.ndim == 0]
    out = {}
    for k in scalar_names:
        vals = [r[k].values.item() for r in runs]
        out[k] = ("case", np.asarray(vals, dtype=object if isinstance(vals[0], str) else None))
    for k in ("time",) + PER_STEP:
        arr = np.full((len(runs), nstep), np.nan)
        for i, r in enumerate(runs):
            arr[i, : r.sizes["step"]] = r[k].values
        out[k] = (("case", "step"), arr)
    arr = np.full((len(runs), nhalv), np.nan)
    for i, r in enumerate(runs):
        if "halving_time" in r:
            arr[i, : r.sizes["halving"]] = r["halving_time"].values
    out["halving_time"] = (("case", "halving"), arr)
    ds = xr.Dataset(out, coords={"case": np.asarray(names, dtype=object), "step": np.arange(nstep)})
    _annotate(ds)
    ds.attrs.update(provenance_attrs(cfg or {}, title="ureterfsi stability matrix (issue 5)",
                                     cases=",".join(names),
                                     scenes="; ".join(f"{k}: {v}" for k, v in SCENES.items()),
                                     energy_safety=runs[0].attrs.get("energy_safety", ""),
                                     volume_tolerance=runs[0].attrs.get("volume_tolerance", "")))
    for r, n in zip(runs, names):
        for key in ("config_hash", "git_commit", "created"):
            if key in r.attrs:
                ds.attrs[f"case_{n}_{key}"] = r.attrs[key]
    return ds


def outcome_table(ds: xr.Dataset) -> str:
    """Markdown table of the per-case outcomes of a combined dataset."""
    lines = ["| case | outcome | max E_kin (J) | E/bound | volume error | min J_ale | max \\|v\\| (mm/s) | halvings | "
             "Newton/step | steps | wall (s) | diagnosis |", "|" + "---|" * 12]
    for i, c in enumerate(ds["case"].values):
        d = ds.isel(case=i)
        lines.append(
            f"| {c} | {d['outcome'].item()} | {d['max_kinetic_energy'].item():.3g} | "
            f"{d['max_energy_ratio'].item():.2g} | {d['volume_error'].item():.2g} | "
            f"{d['min_jacobian'].item():.3f} | {1e3 * d['peak_speed'].item():.3g} | {int(d['step_halvings'].item())} | "
            f"{d['mean_newton_iterations'].item():.1f} | {int(d['steps'].item())} | {d['wall_time'].item():.1f} | "
            f"{d['diagnosis'].item()} |")
    return "\n".join(lines)


def main(argv=None) -> int:
    """python -m ureterfsi.stability [--config ...] [--case NAME ...] [--end T] --out DIR: run cases."""
    import argparse

    from .config import load_config_files

    ap = argparse.ArgumentParser(prog="python -m ureterfsi.stability")
    ap.add_argument("--config", nargs="+", default=["config/config.yaml"])
    ap.add_argument("--case", nargs="*", default=None, help="case names (default: every case)")
    ap.add_argument("--end", type=float, default=None)
    ap.add_argument("--out", default="results/stability")
    args = ap.parse_args(argv)
    logging.basicConfig(level=logging.INFO, format="%(asctime)s %(name)s: %(message)s")
    cfg = load_config_files(args.config)
    chosen = [case_by_name(cfg, n) for n in args.case] if args.case else cases(cfg)
    for c in chosen:
        write_case(run_case(cfg, c, end=args.end), Path(args.out) / f"{c.name}.nc")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
