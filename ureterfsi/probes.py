"""Probes: point evaluation of fields under MPI, von Mises stress, boundary fluxes (split at a radius).

All probes act on the reference (ALE) mesh: a point probe of the displacement gives the Lagrangian
displacement of that material point; fluid quantities are those at the mesh point X, which sits at
X + u(X) in the current configuration.
"""
from __future__ import annotations

import numpy as np
import ufl
from dolfinx import fem, geometry
from mpi4py import MPI

from .fsi import physics
from .tags import INLET, OUTLET


def von_mises(sigma):
    """sigma_vM = sqrt(3/2 s:s), s = sigma - tr(sigma)/3 I (3x3 Cauchy stress, UFL)."""
    s = sigma - ufl.tr(sigma) / 3.0 * ufl.Identity(3)
    return ufl.sqrt(1.5 * ufl.inner(s, s))


def inside_radius(mesh, radius: float, x_axis: float = 0.0):
    """UFL indicator of the reference points closer than `radius` to the axis x = x_axis, y = 0 (3D): 1 inside,
    0 outside. On facets that lie wholly on one side (a conforming mesh, `radius` inside the stent wall) it
    splits a facet integral exactly."""
    X = ufl.SpatialCoordinate(mesh)
    return ufl.conditional(ufl.lt((X[0] - x_axis) ** 2 + X[1] ** 2, radius**2), 1.0, 0.0)


class PointProbe:
    """Evaluate functions at fixed reference points; every rank gets the full result.

    Points outside the mesh give NaN. Points on a partition boundary are evaluated by the lowest
    rank that holds a colliding cell.
    """

    def __init__(self, mesh, points: np.ndarray):
        pts = np.zeros((len(points), 3))
        pts[:, : np.asarray(points).shape[1]] = points
        self.points, self.comm = pts, mesh.comm
        tree = geometry.BoundingBoxTree(mesh, mesh.topology.dim)
        candidates = geometry.compute_collisions(tree, pts)
        colliding = geometry.compute_colliding_cells(mesh, candidates, pts)
        n_local = mesh.topology.index_map(mesh.topology.dim).size_local
        self.local, self.cells = [], []
        for i in range(len(pts)):
            owned = [c for c in colliding.links(i) if c < n_local]
            if owned:
                self.local.append(i)
                self.cells.append(owned[0])
        self.local = np.array(self.local, dtype=np.int64)
        self.cells = np.array(self.cells, dtype=np.int32)
        have = np.full(len(pts), self.comm.size, dtype=np.int32)
        have[self.local] = self.comm.rank
        self.owner = np.zeros_like(have)
        self.comm.Allreduce(have, self.owner, op=MPI.MIN)
        self.mine = self.local[self.owner[self.local] == self.comm.rank]
        self.mine_cells = self.cells[self.owner[self.local] == self.comm.rank]

    def __call__(self, f: fem.Function) -> np.ndarray:
        """Values of f at the points, shape (npoints, value_size)."""
        size = int(np.prod(f.ufl_shape)) if f.ufl_shape else 1
        out = np.zeros((len(self.points), size))
        if self.mine.size:
            out[self.mine] = f.eval(self.points[self.mine], self.mine_cells).reshape(len(self.mine), size)
        total = np.zeros_like(out)
        self.comm.Allreduce(out, total, op=MPI.SUM)
        total[self.owner == self.comm.size] = np.nan
        return total


class CellField:
    """A UFL expression interpolated into a DG space (e.g. von Mises stress at the vertices of each
    cell), with its maximum and location over a set of cells."""

    def __init__(self, mesh, expr, degree: int = 1, cells=None):
        self.space = fem.FunctionSpace(mesh, ("DG", degree))
        self.function = fem.Function(self.space)
        self.expression = fem.Expression(expr, self.space.element.interpolation_points())
        n_local = mesh.topology.index_map(mesh.topology.dim).size_local
        cells = np.arange(n_local, dtype=np.int32) if cells is None else np.asarray(cells, np.int32)
        cells = cells[cells < n_local]
        ndofs = self.space.dofmap.dof_layout.num_dofs
        self.dofs = self.space.dofmap.list.array.reshape(-1, ndofs)[cells].ravel()
        self.coords = self.space.tabulate_dof_coordinates()
        self.comm = mesh.comm

    def update(self) -> fem.Function:
        self.function.interpolate(self.expression)
        return self.function

    def maximum(self):
        """(max value, its reference coordinates) over the cells, reduced over ranks."""
        vals = self.function.x.array[self.dofs]
        if vals.size:
            i = int(np.argmax(vals))
            local = (float(vals[i]), self.coords[self.dofs[i]].tolist())
        else:
            local = (-np.inf, [np.nan] * 3)
        return max(self.comm.allgather(local), key=lambda item: item[0])


def assemble_scalar(form, comm) -> float:
    """Assemble a compiled scalar form and sum over ranks."""
    return float(comm.allreduce(fem.assemble_scalar(form), op=MPI.SUM))


def flux_volume_forms(pb) -> dict:
    """UFL forms, on the reference mesh of the problem `pb`, of the urine volume V = int_fluid J dX and the
    volumetric flow rates through the open ends Q = int (v - w) . J F^-T N dA, w the BDF mesh velocity of
    the last accepted step: "fluid_volume", "outlet_flux" (positive out), "inlet_flux" (positive in)."""
    ops = pb.ops
    v, u = pb.split()["velocity"], pb.split()["displacement"]
    F = physics.deformation_gradient(ops, u)
    J = ufl.det(F)
    n_da = J * ufl.inv(F).T * ops.normal()
    rel = ops.vec(v) - ops.vec(pb.split(pb.x_dot)["displacement"])
    return {"outlet_flux": ufl.dot(rel, n_da) * ops.weight * pb.ds(OUTLET),
            "inlet_flux": -ufl.dot(rel, n_da) * ops.weight * pb.ds(INLET),
            "fluid_volume": J * ops.weight * pb.dx(tuple(pb.fluid_tags))}


def end_face_pressure_forms(pb, inlet: int = INLET, outlet: int = OUTLET) -> dict:
    """UFL forms of the area-mean urine pressure on the open ends (facet tags `inlet`, `outlet`),
    p_face = int p |J F^-T N| dA / int |J F^-T N| dA (current area, ALE): "{inlet,outlet}_pressure_integral" and
    "{inlet,outlet}_area" (their ratio is the mean)."""
    ops = pb.ops
    p, u = pb.split()["pressure"], pb.split()["displacement"]
    F = physics.deformation_gradient(ops, u)
    n_da = ufl.det(F) * ufl.inv(F).T * ops.normal()
    da = ufl.sqrt(ufl.dot(n_da, n_da)) * ops.weight
    return {f"{end}_{k}": (p * da if k == "pressure_integral" else da) * pb.ds(tag)
            for end, tag in (("inlet", inlet), ("outlet", outlet)) for k in ("pressure_integral", "area")}
