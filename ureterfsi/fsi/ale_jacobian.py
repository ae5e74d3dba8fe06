"""The ALE map's Jacobian J = det(I + Grad u) at the vertices of a set of cells: the engine's inversion guard
(MonolithicFSI.min_ale_jacobian) and a mesh motion's quality measured before a run."""
from __future__ import annotations

import math

import numpy as np
import ufl
from dolfinx import fem
from mpi4py import MPI

from . import physics
from .operators import Operators


class ALEJacobian:
    """J = det F, F = I + Grad u, of the displacement u (a Function, or a part of the mixed state) interpolated in
    DG1, i.e. at the vertices of the owned ones among the local `cells`. In r-z (ops.axisymmetric) the hoop stretch
    1 + u_r/r is 0/0 = NaN at vertices on the axis (and NaN <= threshold is False: the guard would never fire); there
    it takes its limit 1 + du_r/dr."""

    def __init__(self, ops: Operators, u, cells: np.ndarray):
        mesh = ops.mesh
        Q = fem.FunctionSpace(mesh, ("DG", 1))
        self.comm = mesh.comm
        self.values = fem.Function(Q)
        F = physics.deformation_gradient(ops, u)
        J = ufl.det(F)
        if ops.axisymmetric:
            g = ufl.grad(u)
            F_axis = ufl.as_tensor([[F[0, 0], 0.0, F[0, 2]], [0.0, 1.0 + g[0, 0], 0.0], [F[2, 0], 0.0, F[2, 2]]])
            J = ufl.conditional(ufl.gt(abs(ops.r), 1e-300), J, ufl.det(F_axis))
        self.expression = fem.Expression(J, Q.element.interpolation_points())
        cells = cells[cells < mesh.topology.index_map(mesh.topology.dim).size_local]
        self.dofs = np.unique(Q.dofmap.list.array.reshape(-1, Q.dofmap.dof_layout.num_dofs)[cells].ravel())
        self._coordinates = None        # of self.dofs, tabulated at the first minimum_at

    def minimum(self) -> float:
        """min J over the vertices, reduced over ranks (1 when undeformed, <= 0 when inverted)."""
        self.values.interpolate(self.expression)
        local = self.values.x.array[self.dofs].min() if self.dofs.size else np.inf
        return float(self.comm.allreduce(local, MPI.MIN))

    def minimum_at(self) -> tuple:
        """(min J, reference coordinates (x, y, z) of its vertex), reduced over ranks; a non-finite J counts as -inf
        (and is the place); (inf, (NaN, NaN, NaN)) without vertices."""
        self.values.interpolate(self.expression)
        vals = self.values.x.array[self.dofs]
        local = (math.inf, (math.nan,) * 3)
        if vals.size:
            bad = ~np.isfinite(vals)
            i = int(np.argmax(bad)) if bad.any() else int(np.argmin(vals))
            if self._coordinates is None:
                self._coordinates = self.values.function_space.tabulate_dof_coordinates()[self.dofs]
            local = (-math.inf if bad.any() else float(vals[i]), tuple(float(c) for c in self._coordinates[i]))
        return min(self.comm.allgather(local), key=lambda item: item[0])
