"""Wall shear stress and the flux through channels of a fluid, read from a problem's state (any scene).

Wall shear stress (WSS): the tangential part of the traction the fluid exerts on a wall, in the current
configuration of the ALE mesh,
    tau_w = sigma_f n - (n . sigma_f n) n,   n = -J F^-T N / |J F^-T N|  (the wall's normal, into the fluid),
    sigma_f = -p I + mu (grad_x v + grad_x v^T)   (ureterfsi.fsi.physics.fluid_cauchy_stress).
WallShear evaluates it as the mean over the wall facets of each fluid cell (one value per cell and wall region,
`tau_u = int tau_w da / int da`), on exterior facets (a fluid-alone mesh) and on interior ones (a fluid-solid
interface: the fluid side's traction). WallShearHistory integrates those values over time: the time-averaged WSS
TAWSS = (1/T) int |tau_w| dt and the oscillatory shear index OSI = 1/2 (1 - |int tau_w dt| / int |tau_w| dt)
(Ku et al. 1985, Arteriosclerosis 5:293), trapezoidal rule over the observed steps.

ChannelFlux: net and gross flux through channels (sets of fluid cells) crossed by the level sets of a function chi
that goes from 0 to 1 across each channel: Q = int_C J F^-1 (v - w) . Grad chi dX, the mean over the level sets
chi = s of the flux through them (exact for a divergence-free field), and the gross
E = int_C J |F^-1 (v - w) . Grad chi| dX, the mean over the level sets of int |u.n| da (E >= |Q|, E = |Q| for a flow
that crosses the channel in one direction).
"""
from __future__ import annotations

import numpy as np
import ufl
from dolfinx import fem
from dolfinx.fem import petsc as fem_petsc
from dolfinx.mesh import meshtags
from mpi4py import MPI
from petsc4py import PETSc

from . import physics


def tangential_traction(sigma, n):
    """tau = sigma n - (n . sigma n) n: the tangential part of the traction sigma n on a surface of unit normal n."""
    t = sigma * n
    return t - ufl.dot(n, t) * n


class WallShear:
    """Facet-mean wall shear stress on wall regions of a problem `pb` (MonolithicFSI) with one fluid.

    `regions`: {name: local facet indices} on the fluid's boundary (exterior facets, or interior facets between a
    fluid and a solid cell). Regions whose facets share no fluid cell are assembled together: `groups` lists the
    region names of each assembly (default: one per region). After update(): per local owned fluid cell touching
    a region's facets (a `unit`), `traction[u]` (3, Pa), `area[u]` (m^2, current), `region[u]` (index in
    `names`); area_mean(name) = int |tau_w| da / int da over the units of a region."""

    def __init__(self, pb, regions: dict, groups=None, quadrature_degree: int = 4):
        mesh, ops = pb.mesh, pb.ops
        tdim = mesh.topology.dim
        self.names = list(regions)
        self.comm = pb.comm
        ids = {name: k + 1 for k, name in enumerate(self.names)}
        facets = np.concatenate([np.asarray(regions[n], np.int32) for n in self.names] or [np.zeros(0, np.int32)])
        values = np.concatenate([np.full(len(regions[n]), ids[n], np.int32) for n in self.names]
                                or [np.zeros(0, np.int32)])
        order = np.argsort(facets)
        if np.unique(facets).size != facets.size:
            raise ValueError("WallShear: a facet belongs to two regions")
        tags = meshtags(mesh, tdim - 1, facets[order], values[order])
        md = {"quadrature_degree": quadrature_degree}
        ds = ufl.Measure("ds", domain=mesh, subdomain_data=tags, metadata=md)
        dS = ufl.Measure("dS", domain=mesh, subdomain_data=tags, metadata=md)

        fluid_cells = pb.cells(pb.fluid_tags)
        chi = fem.Function(fem.FunctionSpace(mesh, ("DG", 0)))
        chi.x.array[chi.function_space.dofmap.list.array[fluid_cells]] = 1.0
        X = pb.split()
        v, p, u = X["velocity"], X["pressure"], X["displacement"]
        F = physics.deformation_gradient(ops, u)
        sigma = physics.fluid_cauchy_stress(ops, pb.scene.fluid.material, v, p, F)
        n_da = -ufl.det(F) * ufl.inv(F).T * ops.normal()      # wall normal (into the fluid) times da/dA
        da = ufl.sqrt(ufl.dot(n_da, n_da))
        integrand = ufl.as_vector([*(tangential_traction(sigma, n_da / da) * da), da]) * ops.weight
        Q = fem.VectorFunctionSpace(mesh, ("DG", 0), dim=4)
        q = ufl.TestFunction(Q)
        groups = groups or [[n] for n in self.names]
        group_of = {n: k for k, g in enumerate(groups) for n in g}
        self.forms = []
        for group in groups:
            gid = tuple(ids[n] for n in group)
            form = ufl.inner(integrand, q) * ds(gid) + sum(
                chi(s) * ufl.inner(integrand(s), q(s)) for s in "+-") * dS(gid)
            self.forms.append(fem.form(form))
        self.vec = fem_petsc.create_vector(self.forms[0])

        # units: the owned fluid cells touching a region's facets, one per (cell, region)
        mesh.topology.create_connectivity(tdim - 1, tdim)
        f2c = mesh.topology.connectivity(tdim - 1, tdim)
        n_local = mesh.topology.index_map(tdim).size_local
        is_fluid = np.zeros(n_local + mesh.topology.index_map(tdim).num_ghosts, bool)
        is_fluid[fluid_cells] = True
        units = sorted({(int(c), int(r) - 1) for f, r in zip(facets, values) for c in f2c.links(f)
                        if c < n_local and is_fluid[c]})
        self.unit_cells = np.array([c for c, _ in units], np.int32).reshape(-1)
        self.region = np.array([r for _, r in units], np.int64).reshape(-1)
        self.unit_group = np.array([group_of[self.names[r]] for r in self.region], np.int64).reshape(-1)
        for k in range(len(groups)):
            cells = self.unit_cells[self.unit_group == k]
            if np.unique(cells).size != cells.size:
                raise ValueError(f"WallShear: a fluid cell touches two regions of the assembly group {groups[k]}")
        self.dofs = Q.dofmap.list.array[self.unit_cells] if self.unit_cells.size else np.zeros(0, np.int32)
        self.traction = np.zeros((self.unit_cells.size, 3))
        self.area = np.zeros(self.unit_cells.size)

    def update(self) -> None:
        """Assemble the facet integrals of the current state into the units' traction and area."""
        for k, form in enumerate(self.forms):
            with self.vec.localForm() as loc:
                loc.set(0.0)
            fem_petsc.assemble_vector(self.vec, form)
            self.vec.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
            sel = self.unit_group == k
            block = self.vec.array.reshape(-1, 4)[self.dofs[sel]]
            self.area[sel] = block[:, 3]
            self.traction[sel] = block[:, :3] / np.where(block[:, 3] > 0, block[:, 3], 1.0)[:, None]

    def area_mean(self, name: str) -> float:
        """int |tau_w| da / int da over region `name` (facet-mean values), summed over ranks."""
        sel = self.region == self.names.index(name)
        local = np.array([np.sum(np.linalg.norm(self.traction[sel], axis=1) * self.area[sel]), self.area[sel].sum()])
        total = np.zeros(2)
        self.comm.Allreduce(local, total, op=MPI.SUM)
        return float(total[0] / total[1]) if total[1] > 0 else float("nan")


class WallShearHistory:
    """Time integrals of the units' wall shear stress of a WallShear (trapezoidal rule over the observed times):
    int tau_w dt, int |tau_w| dt and int da dt per unit; TAWSS, OSI and the area fraction below a threshold."""

    def __init__(self, n_units: int):
        self.start = self.last_time = None
        self.last_traction = np.zeros((n_units, 3))
        self.last_area = np.zeros(n_units)
        self.vector = np.zeros((n_units, 3))
        self.magnitude = np.zeros(n_units)
        self.area_time = np.zeros(n_units)

    def add(self, time: float, traction: np.ndarray, area: np.ndarray) -> None:
        if self.last_time is None:
            self.start = time
        else:
            h = 0.5 * (time - self.last_time)
            self.vector += h * (self.last_traction + traction)
            self.magnitude += h * (np.linalg.norm(self.last_traction, axis=1) + np.linalg.norm(traction, axis=1))
            self.area_time += h * (self.last_area + area)
        self.last_time, self.last_traction, self.last_area = time, np.array(traction), np.array(area)

    @property
    def duration(self) -> float:
        return 0.0 if self.last_time is None else self.last_time - self.start

    def tawss(self) -> np.ndarray:
        """(1/T) int |tau_w| dt per unit (Pa)."""
        return self.magnitude / self.duration

    def osi(self) -> np.ndarray:
        """1/2 (1 - |int tau_w dt| / int |tau_w| dt) per unit (0 where the wall saw no shear)."""
        m = np.where(self.magnitude > 0, self.magnitude, 1.0)
        return np.where(self.magnitude > 0, 0.5 * (1.0 - np.linalg.norm(self.vector, axis=1) / m), 0.0)

    def weights(self) -> np.ndarray:
        """Time-mean current area of each unit (m^2): the area weights of the region means."""
        return self.area_time / self.duration

    def region_summary(self, region: np.ndarray, n_regions: int, threshold: float, comm) -> dict:
        """Per region (units' `region` index 0..n_regions-1), summed over ranks: area-weighted mean TAWSS and OSI
        and the area fraction whose TAWSS is below `threshold` (Pa); NaN for a region without area."""
        w, tawss = self.weights(), self.tawss()
        local = np.zeros((n_regions, 4))
        for col, val in enumerate((w * tawss, w * self.osi(), w * (tawss < threshold), w)):
            np.add.at(local[:, col], region, val)
        total = np.zeros_like(local)
        comm.Allreduce(local, total, op=MPI.SUM)
        area = np.where(total[:, 3] > 0, total[:, 3], np.nan)
        return {"tawss": total[:, 0] / area, "osi": total[:, 1] / area, "low_wss_area_fraction": total[:, 2] / area}

    def state(self) -> dict:
        return {k: (v.tolist() if isinstance(v, np.ndarray) else v) for k, v in vars(self).items()}

    def load_state(self, state: dict) -> None:
        for k, v in state.items():
            setattr(self, k, np.asarray(v, dtype=float) if isinstance(v, list) else v)


class ChannelFlux:
    """Net and gross flux through channels of a problem `pb`'s fluid: `grad_chi` the UFL gradient (reference
    configuration) of a function chi rising from 0 to 1 across every channel, `channels` the local cells of each
    (the module docstring); outward (along Grad chi) positive; summed over ranks."""

    def __init__(self, pb, grad_chi, channels):
        ops = pb.ops
        X, Xdot = pb.split(), pb.split(pb.x_dot)
        F = physics.deformation_gradient(ops, X["displacement"])
        crossing = ufl.det(F) * ufl.dot(ufl.inv(F) * (ops.vec(X["velocity"]) - ops.vec(Xdot["displacement"])),
                                        grad_chi) * ops.weight
        Q = fem.FunctionSpace(pb.mesh, ("DG", 0))
        q = ufl.TestFunction(Q)
        dx = pb.dx(tuple(pb.fluid_tags))
        self.forms = [fem.form(crossing * q * dx), fem.form(abs(crossing) * q * dx)]
        self.vec = fem_petsc.create_vector(self.forms[0])
        n_local = pb.mesh.topology.index_map(pb.mesh.topology.dim).size_local
        self.dofs = [Q.dofmap.list.array[np.asarray(c, np.int32)[np.asarray(c) < n_local]] for c in channels]
        self.comm = pb.comm

    def __call__(self) -> tuple[np.ndarray, np.ndarray]:
        """(net, gross) flux of each channel (m^3 s^-1)."""
        out = []
        for form in self.forms:
            with self.vec.localForm() as loc:
                loc.set(0.0)
            fem_petsc.assemble_vector(self.vec, form)
            arr = self.vec.array
            local = np.array([arr[d].sum() for d in self.dofs])
            total = np.zeros_like(local)
            self.comm.Allreduce(local, total, op=MPI.SUM)
            out.append(total)
        return out[0], out[1]
