"""The per-case observer of the stability matrix: energy, volume balance, solver effort and limits after
every accepted step (docs/stability.md)."""
from __future__ import annotations

import math
import time as _time

import numpy as np
import ufl
from dolfinx import fem
from dolfinx.fem import petsc as fem_petsc
from mpi4py import MPI

from ..fsi import LinearElastic, MonolithicFSI, MooneyRivlin, Observer, physics
from ureterfsi.mesh import tags
from ureterfsi.fsi.probes import assemble_scalar, flux_volume_forms
from .dataset import SERIES
from .limits import StabilityLimit

# what the rows of each field of the monolithic system are
ROWS = {"velocity": "momentum (velocity)", "displacement": "kinematic / mesh-motion (displacement)",
        "pressure": "continuity (fluid pressure)", "solid_pressure": "volumetric constraint (solid pressure)"}


class StabilityObserver(Observer):
    """Records SERIES after every accepted step; raises StabilityLimit at the energy, NaN and wall-time limits.

    Assembled on the reference mesh (r-z: the weight 2 pi r, the whole tube):
      kinetic energy  E = int_fluid 1/2 rho |v|^2 J + int_solid 1/2 rho0 |v|^2, elastic energy int_solid W(F);
      external power  of the load (int t . v), of the open-boundary normal stress and of the prescribed motion
                      sum_i R_i v_i (R the residual without boundary conditions: the consistent reaction);
      volume balance  V(t) against V(0) - int_0^t Q dt, the flux integrated with each step's BDF weights;
      energy limit    E(t) > energy_safety * (E(0) + E_el(0) + W(t)), W = int |P_load| + |P_open| + |P_prescribed|.
    """

    def __init__(self, pb: MonolithicFSI, st: dict, wall0: float | None = None):
        self.pb, self.st, self.comm = pb, st, pb.comm
        self.wall0 = _time.perf_counter() if wall0 is None else wall0
        ops, dx, ds, sc = pb.ops, pb.dx, pb.ds, pb.scene
        X = pb.split()
        V, u = ops.vec(X["velocity"]), X["displacement"]
        F = physics.deformation_gradient(ops, u)
        J = ufl.det(F)
        n_da = J * ufl.inv(F).T * ops.normal()
        w = ops.weight
        forms = flux_volume_forms(pb, tags.INLET, tags.OUTLET)
        rho = sc.fluid.material.density
        forms["kinetic_energy_fluid"] = 0.5 * rho * ufl.dot(V, V) * J * w * dx(tuple(pb.fluid_tags))
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
        # the power of every external load on the solid: tractions, follower pressures, body forces
        p_load = sum((ufl.dot(load.traction(X_ref, pb.t, ops.normal()), V) * w * ds(tuple(load.tags))
                      for load in sc.loads), 0)
        p_load += sum((ufl.dot(physics.follower_pressure_traction(ops, load.pressure(X_ref, pb.t), u), V) * w
                       * ds(tuple(load.tags)) for load in sc.pressure_loads), 0)
        p_load += sum((ufl.dot(load.force(X_ref, pb.t), V) * w * dx(tuple(load.tags)) for load in sc.body_forces), 0)
        p_open = sum((-ob.normal_stress * ufl.dot(n_da, V) * w * ds(tuple(ob.tags)) for ob in sc.open_boundaries), 0)
        forms.update(kinetic_energy_solid=ke_s, elastic_energy=el, load_power=p_load, open_boundary_power=p_open)
        self.forms = {k: fem.form(f) for k, f in forms.items() if not isinstance(f, (int, float))}
        self.absent = [k for k, f in forms.items() if isinstance(f, (int, float))]

        # the consistent reaction times the velocity, over the owned velocity dofs of the mixed space
        self.reaction = fem_petsc.create_vector(pb.residual_form)
        vdofs = np.asarray(pb.sub("velocity").collapse()[1])
        n_owned = pb.W.dofmap.index_map.size_local * pb.W.dofmap.index_map_bs
        self.velocity_dofs = vdofs[vdofs < n_owned]
        self.axisymmetric = ops.axisymmetric
        # dof coordinates of every field of the mixed space (diagnosis of the place)
        self.fields = []
        for name in pb.field_names:
            Vc, dofs = pb.sub(name).collapse()
            self.fields.append((name, np.asarray(dofs), Vc.dofmap.index_map_bs, Vc.tabulate_dof_coordinates()))
        self.displacement_dofs = self.fields[pb.index["displacement"]][1]
        self.series = {k: [] for k in SERIES}
        self.volume_from_flux = []
        self.work = 0.0
        self.initial_energy = math.nan

    def rz(self, xyz):
        """Reference (r, z) of a coordinate: (x, y) in r-z, (sqrt(x^2 + y^2), z) in 3D."""
        return (xyz[0], xyz[1]) if self.axisymmetric else (math.hypot(xyz[0], xyz[1]), xyz[2])

    def prescribed_power(self) -> float:
        """sum_i R_i v_i: the power the Dirichlet conditions put into the system."""
        self.pb.assemble_reaction(self.reaction)
        d = self.velocity_dofs
        return float(self.comm.allreduce(float(np.dot(self.reaction.array_r[d], self.pb.x.x.array[d])), op=MPI.SUM))

    def min_jacobian(self):
        """(min ALE Jacobian over the fluid vertices, its reference (r, z))."""
        jmin, xyz = self.pb.min_ale_jacobian_at()
        return jmin, self.rz(xyz)

    def fastest_node(self):
        """(max |v|, its reference (r, z)) over the whole mesh (NaN entries first)."""
        _, dofs, bs, xyz = self.fields[self.pb.index["velocity"]]
        speed = np.sqrt((self.pb.x.x.array[dofs].reshape(-1, bs) ** 2).sum(axis=1))
        bad = ~np.isfinite(speed)
        i = int(np.argmax(bad)) if bad.any() else int(np.argmax(speed)) if speed.size else 0
        local = (-math.inf if bad.any() else (-float(speed[i]) if speed.size else math.inf),
                 self.rz(xyz[i]) if speed.size else (math.nan, math.nan))
        val, where = min(self.comm.allgather(local), key=lambda t: t[0])
        return -val, where

    def largest_residual(self):
        """(rows, |R| entry, reference (r, z)) of the largest (or first non-finite) entry of the last
        assembled Newton residual, e.g. the last iterate of a failed step."""
        b = self.pb.b.array
        best = (-math.inf, "", (math.nan, math.nan))
        for name, dofs, bs, xyz in self.fields:
            idx = np.flatnonzero(dofs < b.size)      # owned entries of the residual vector
            vals = np.abs(b[dofs[idx]])
            if not vals.size:
                continue
            bad = ~np.isfinite(vals)
            j = int(np.argmax(bad)) if bad.any() else int(np.argmax(vals))
            val = math.inf if bad.any() else float(vals[j])
            if val > best[0]:
                best = (val, ROWS.get(name, name), tuple(self.rz(xyz[idx[j] // bs])))
        val, name, where = max(self.comm.allgather(best), key=lambda t: t[0])
        return name, val, where

    def observe(self, pb: MonolithicFSI, step: int) -> None:
        val = {k: assemble_scalar(f, self.comm) for k, f in self.forms.items()} | {k: 0.0 for k in self.absent}
        val["prescribed_power"] = self.prescribed_power()
        dt = float(pb.dt.value) if step else 0.0
        b0, b1, b2 = (float(c.value) for c in pb.bdf) if step else (1.0, 0.0, 0.0)
        q = val["outlet_flux"] - val["inlet_flux"]
        vb = self.volume_from_flux
        if step == 0:
            vb[:] = [val["fluid_volume"]]
            self.initial_energy = val["kinetic_energy_fluid"] + val["kinetic_energy_solid"] + val["elastic_energy"]
        else:
            vb.append((-dt * q - b1 * vb[-1] - b2 * (vb[-2] if len(vb) >= 2 else 0.0)) / b0)
            self.work += dt * (abs(val["load_power"]) + abs(val["open_boundary_power"]) + abs(val["prescribed_power"]))
        ke = val["kinetic_energy_fluid"] + val["kinetic_energy_solid"]
        jmin = pb.min_ale_jacobian()
        umax = self.comm.allreduce(float(np.nanmax(np.abs(pb.x.x.array[self.displacement_dofs]), initial=0.0)),
                                   op=MPI.MAX)
        bound = self.initial_energy + self.work
        vmax, _ = self.fastest_node()
        row = {"time": pb.time, "dt": dt, "kinetic_energy": ke, "energy_bound": bound, "max_speed": vmax,
               "external_work": self.work, "volume_from_flux": vb[-1], "min_ale_jacobian": jmin,
               "max_displacement": umax, **val}
        for k in SERIES:
            self.series[k].append(row[k])
        t = pb.time
        bad = [k for k, x in row.items() if not math.isfinite(x)]
        if bad:
            _, where = self.fastest_node()
            raise StabilityLimit("nan", f"non-finite {', '.join(bad)} at t = {t:.6g} s (step {step})", t, where,
                                 "fastest (or first non-finite) node")
        if ke > self.st["energy_safety"] * bound:
            _, where = self.fastest_node()
            raise StabilityLimit(
                "energy", f"kinetic energy {ke:.3e} J exceeds {self.st['energy_safety']:g} x the bound "
                f"E(0) + E_el(0) + W(t) = {bound:.3e} J at t = {t:.6g} s (step {step})", t, where,
                f"fastest node, |v| = {vmax:.3e} m/s, at")
        if _time.perf_counter() - self.wall0 > self.st["max_wall_time"]:
            raise StabilityLimit("wall_time", f"wall-time budget stability.max_wall_time = "
                                 f"{self.st['max_wall_time']:g} s exceeded at t = {t:.6g} s (step {step})", t)
