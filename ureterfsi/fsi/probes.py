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

from ureterfsi.fsi import physics


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

    A point in several cells (on a face, an edge or a vertex) takes the mean of its cells' values: a discontinuous
    field (a cell field, CellField) is several-valued there, and the mean depends neither on the partition nor on the
    cell numbering (a continuous field has one value). `within`: the local cells on which the functions are
    defined (e.g. a CellField's), the only ones a point's mean is over; all by default. Points in none give NaN.
    `cells`: a local cell holding each point (-1: none on this rank) instead of the collision search, whose
    tolerance misses points on a faceted boundary (surface_line_points).
    """

    def __init__(self, mesh, points: np.ndarray, cells: np.ndarray | None = None, within: np.ndarray | None = None):
        pts = np.zeros((len(points), 3))
        pts[:, : np.asarray(points).shape[1]] = points
        self.points, self.comm = pts, mesh.comm
        if cells is None:
            tree = geometry.BoundingBoxTree(mesh, mesh.topology.dim)
            candidates = geometry.compute_collisions(tree, pts)
            colliding = geometry.compute_colliding_cells(mesh, candidates, pts)
            links = [colliding.links(i) for i in range(len(pts))]
        else:
            links = [[c] if c >= 0 else [] for c in cells]
        n_local = mesh.topology.index_map(mesh.topology.dim).size_local
        allowed = None if within is None else set(np.asarray(within, dtype=np.int64).tolist())
        pairs = [(i, c) for i in range(len(pts)) for c in links[i]
                 if c < n_local and (allowed is None or c in allowed)]
        self.pair_points = np.array([i for i, _ in pairs], dtype=np.int64)
        self.pair_cells = np.array([c for _, c in pairs], dtype=np.int32)
        local = np.bincount(self.pair_points, minlength=len(pts)).astype(np.int64)
        self.count = np.zeros_like(local)
        self.comm.Allreduce(local, self.count, op=MPI.SUM)

    @property
    def missing(self) -> np.ndarray:
        """Indices of the points in no cell (of `within`) on any rank."""
        return np.flatnonzero(self.count == 0)

    def __call__(self, f: fem.Function) -> np.ndarray:
        """Values of f at the points, shape (npoints, value_size): the mean over each point's cells."""
        size = int(np.prod(f.ufl_shape)) if f.ufl_shape else 1
        out = np.zeros((len(self.points), size))
        if self.pair_points.size:
            values = f.eval(self.points[self.pair_points], self.pair_cells).reshape(len(self.pair_points), size)
            np.add.at(out, self.pair_points, values)
        total = np.zeros_like(out)
        self.comm.Allreduce(out, total, op=MPI.SUM)
        found = self.count > 0
        total[found] /= self.count[found, None]
        total[~found] = np.nan
        return total


def surface_line_points(mesh, facets: np.ndarray, z: np.ndarray, axisymmetric: bool) -> tuple[np.ndarray, np.ndarray]:
    """(points, cells): where the meridian x > 0, y = 0 (3D; in r-z the surface itself) meets the faceted surface of
    the local `facets` at each axial position z, and a local cell holding each point (-1: none on this rank).

    The points lie on the mesh's own (straight-sided) facets, not on the curved reference surface they approximate:
    a point on the curved surface lies outside the mesh where the facet chords cut inside it (up to 60 um on a
    stricture's flank, 6 um around a cylinder with no mesh edge on the meridian: the 10 mm coarse meshes), where the
    collision search finds no cell."""
    tdim = mesh.topology.dim
    for d in ((tdim - 1, tdim), (tdim - 1, 0), (tdim, 0)):
        mesh.topology.create_connectivity(*d)
    f2c, f2v, c2v = (mesh.topology.connectivity(*d) for d in ((tdim - 1, tdim), (tdim - 1, 0), (tdim, 0)))
    x, cell_nodes = mesh.geometry.x, mesh.geometry.dofmap
    # a facet's geometry nodes: its vertices' positions among its cell's (the first geometry nodes of a cell are
    # its vertices, in the cell's vertex order)
    nodes = [cell_nodes.links(f2c.links(f)[0])[[list(c2v.links(f2c.links(f)[0])).index(v) for v in f2v.links(f)]]
             for f in facets]
    zi, n_local = 1 if axisymmetric else 2, mesh.topology.index_map(tdim).size_local
    tol = 1e-12 * max(float(np.abs(x).max()) if x.size else 1.0, 1e-300)
    segments = []                                          # (z_a, r_a, z_b, r_b, cell)
    for f, vs in zip(facets, nodes):
        p = x[vs]
        if axisymmetric:
            cut = p[:, [0, 1]]
        else:
            y = np.where(np.abs(p[:, 1]) <= tol, 0.0, p[:, 1])
            if y.min() > 0 or y.max() < 0 or p[:, 0].max() <= 0:
                continue
            cut = [p[i, [0, 2]] for i in range(len(p)) if y[i] == 0.0]
            for i in range(len(p)):
                j = (i + 1) % len(p)
                if y[i] * y[j] < 0:
                    cut.append((p[i] + y[i] / (y[i] - y[j]) * (p[j] - p[i]))[[0, 2]])
            cut = np.asarray(cut).reshape(-1, 2)
            cut = cut[cut[:, 0] > 0]
            if not len(cut):
                continue
        a, b = cut[np.argmin(cut[:, 1])], cut[np.argmax(cut[:, 1])]
        segments.append((a[1], a[0], b[1], b[0], f2c.links(f)[0]))
    seg = np.asarray(segments, dtype=float).reshape(-1, 5)
    pts, cells = np.zeros((len(z), 3)), np.full(len(z), -1, dtype=np.int32)
    for k, zk in enumerate(np.asarray(z, dtype=float)):
        hit = np.flatnonzero((seg[:, 0] <= zk + tol) & (zk <= seg[:, 2] + tol))
        if not hit.size:
            continue
        owned = hit[seg[hit, 4] < n_local]                  # an owned cell where this rank has one
        za, ra, zb, rb, c = seg[owned[0] if owned.size else hit[0]]
        r = ra if zb == za else ra + (zk - za) / (zb - za) * (rb - ra)
        pts[k, 0], pts[k, zi], cells[k] = r, zk, int(c)
    return pts, cells


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


def flux_volume_forms(pb, inlet: int, outlet: int) -> dict:
    """UFL forms, on the reference mesh of the problem `pb`, of the urine volume V = int_fluid J dX and the
    volumetric flow rates through the open ends (facet tags `inlet`, `outlet`) Q = int (v - w) . J F^-T N dA, w the BDF mesh velocity of
    the last accepted step: "fluid_volume", "outlet_flux" (positive out), "inlet_flux" (positive in), and
    "fluid_volume_rate" S = int J tr(Grad w F^-1) dX = int_boundary w . n da, the volume rate the continuity rows
    balance: with v = w on the walls they make Q_in - Q_out = S to the solver's tolerance. S is not the BDF
    derivative of V: the scheme evaluates w . n da on the step's end configuration, while V changes by
    int_step int w . n(t) da dt (the discrete geometric conservation law does not hold), so the two differ by
    O(dt^k), k the BDF order (docs/end-conditions.md)."""
    ops = pb.ops
    v, u = pb.split()["velocity"], pb.split()["displacement"]
    F = physics.deformation_gradient(ops, u)
    J = ufl.det(F)
    n_da = J * ufl.inv(F).T * ops.normal()
    w = pb.split(pb.x_dot)["displacement"]
    rel = ops.vec(v) - ops.vec(w)
    fluid = pb.dx(tuple(pb.fluid_tags))
    return {"outlet_flux": ufl.dot(rel, n_da) * ops.weight * pb.ds(outlet),
            "inlet_flux": -ufl.dot(rel, n_da) * ops.weight * pb.ds(inlet),
            "fluid_volume": J * ops.weight * fluid,
            "fluid_volume_rate": J * ufl.tr(ops.grad(w) * ufl.inv(F)) * ops.weight * fluid}


def cut_flux_forms(pb, z_cut: float, radius: float, x_axis: float = 0.0) -> tuple[dict, fem.Function]:
    """UFL forms (3D) of the volumetric flow rate in +z through the plane z = z_cut, consistent with the continuity
    rows: Q_cut = -int cof F Grad q . (v - w) dX over the fluid, q the P1 pressure-space indicator of the fluid's
    vertices with z < z_cut (nonzero only on the layer of cells the plane crosses). The continuity rows hold
    int J tr(Grad v F^-1) q dX = 0, so Q_in = Q_cut + the rate of change of the urine volume upstream, to the
    solver's tolerance (docs/stricture.md). "cut_flux": all of it; "cut_inside_flux": the part at reference points
    closer than `radius` to the axis x = x_axis, y = 0 (inside_radius). Returns the forms and q (keep it alive)."""
    ops, tdim = pb.ops, pb.mesh.topology.dim
    P, _ = pb.sub("pressure").collapse()
    dofs = fem.locate_dofs_topological(P, tdim, pb.cells(tuple(pb.fluid_tags)))
    q = fem.Function(P)
    q.x.array[dofs[P.tabulate_dof_coordinates()[dofs, 2] < z_cut]] = 1.0
    u = pb.split()["displacement"]
    F = physics.deformation_gradient(ops, u)
    cof = ufl.det(F) * ufl.inv(F).T
    rel = ops.vec(pb.split()["velocity"]) - ops.vec(pb.split(pb.x_dot)["displacement"])
    cut, dx = -ufl.dot(cof * ufl.grad(q), rel), pb.dx(tuple(pb.fluid_tags))
    return {"cut_flux": cut * dx, "cut_inside_flux": inside_radius(pb.mesh, radius, x_axis) * cut * dx}, q


def end_face_pressure_forms(pb, inlet: int, outlet: int) -> dict:
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
