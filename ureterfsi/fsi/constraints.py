"""Constraints of the engine's Newton system (MonolithicFSI): the scene's Dirichlet conditions, the pinned rows that
belong to no physics, and the mesh-motion rows removed where the solid or a Dirichlet condition moves the mesh."""
from __future__ import annotations

import numpy as np
from dolfinx import fem
from petsc4py import PETSc

from .dofs import DofLayout


def dirichlet_bcs(cond, base, facet_tags) -> list:
    """[(DirichletBC, value function, component)] of a DirichletCondition on the space `base` (a space or a
    subspace of a mixed space): the whole vector, or each listed component; values start at zero."""
    fdim = base.mesh.topology.dim - 1
    facets = np.unique(np.concatenate([facet_tags.find(t) for t in cond.tags])).astype(np.int32)
    out = []
    for c in [None] if cond.components is None else list(cond.components):
        space = base if c is None else base.sub(c)
        if space.component():      # a subspace: the value lives in its collapsed space
            collapsed, _ = space.collapse()
            g = fem.Function(collapsed)
            bc = fem.dirichletbc(g, fem.locate_dofs_topological((space, collapsed), fdim, facets), space)
        else:
            g = fem.Function(space)
            bc = fem.dirichletbc(g, fem.locate_dofs_topological(space, fdim, facets))
        out.append((bc, g, c))
    return out


class Constraints:
    """The constraints on the mixed space of `layout`:

    - `dirichlet`: the scene's `conditions` (DirichletCondition on `facet_tags`), time-dependent values set by
      `update(t)`; with a segregated mesh motion (`mirror`: the mesh displacement and its dofs in W) the displacement
      conditions constrain the mesh-motion problem instead (`mesh`), and every displacement dof of W mirrors it;
    - `pins` (zero): the pressure dofs of solid cells only, the solid-pressure dofs of `other_cells` (the cells
      outside the Mooney-Rivlin solids; None: no solid pressure);
    - `bcs`: both, and `constrained`: their local dofs (ghosts included); `mesh_rows` and `mesh_rows_local`: the mesh-motion rows removed (global and owned local indices),
      at the interface displacement dofs and the Dirichlet rows.

    `fluid_cells`, `solid_cells`: local cells of the regions (None: the scene has no such region)."""

    def __init__(self, layout: DofLayout, conditions, facet_tags, fluid_cells, solid_cells, other_cells=None,
                 mirror=None):
        self.dirichlet, self.mesh, self.updates = [], [], []
        for cond in conditions:
            if mirror is not None and cond.field == "displacement":
                self.mesh += self._conditions(cond, mirror[0].function_space, facet_tags)
            else:
                self.dirichlet += self._conditions(cond, layout.sub(cond.field), facet_tags)
        if mirror is not None:
            dofs = [np.asarray(mirror[1], dtype=np.int32), np.arange(len(mirror[1]), dtype=np.int32)]
            self.dirichlet.append(fem.dirichletbc(mirror[0], dofs, layout.sub("displacement")))

        tdim = layout.W.mesh.topology.dim
        zero = PETSc.ScalarType(0.0)
        coupled = fluid_cells is not None and solid_cells is not None
        self.pins = []
        if coupled:
            P = layout.sub("pressure")
            in_fluid = fem.locate_dofs_topological(P, tdim, fluid_cells)
            in_solid = fem.locate_dofs_topological(P, tdim, solid_cells)
            pinned = np.setdiff1d(in_solid, in_fluid).astype(np.int32)
            self.pins.append(fem.dirichletbc(zero, pinned, P))
        if other_cells is not None:
            Q = layout.sub("solid_pressure")
            self.pins.append(fem.dirichletbc(zero, fem.locate_dofs_topological(Q, tdim, other_cells), Q))
        self.bcs = self.dirichlet + self.pins
        self.constrained = np.concatenate([np.zeros(0, np.int32)] + [bc.dof_indices()[0] for bc in self.bcs])

        U = layout.sub("displacement")
        if coupled:
            interface = np.intersect1d(fem.locate_dofs_topological(U, tdim, fluid_cells),
                                       fem.locate_dofs_topological(U, tdim, solid_cells))
        else:
            interface = np.zeros(0, np.int32)
        rows = np.unique(np.concatenate([interface] + [bc.dof_indices()[0] for bc in self.dirichlet]))
        rows = rows[rows < layout.owned_size]
        self.mesh_rows = (rows + layout.offset).astype(PETSc.IntType)
        self.mesh_rows_local = rows.astype(np.int32)

    def _conditions(self, cond, base, facet_tags) -> list:
        bcs = []
        for bc, g, comp in dirichlet_bcs(cond, base, facet_tags):
            bcs.append(bc)
            if cond.value is not None:
                self.updates.append((g, cond.value, comp))
        return bcs

    def update(self, t: float) -> None:
        """The time-dependent Dirichlet values at time t."""
        for g, value, comp in self.updates:
            if comp is None:
                g.interpolate(lambda x: value(x, t))
            else:
                g.interpolate(lambda x: np.asarray(value(x, t)).reshape(-1))
