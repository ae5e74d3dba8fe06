"""The dofs of the engine's mixed space by field and by split, as owned local dofs and as PETSc index sets."""
from __future__ import annotations

import numpy as np
from dolfinx import fem
from petsc4py import PETSc


class DofLayout:
    """The mixed space `W` (fields `field_names`, in order): `owned_size` owned local dofs, `offset` the global index
    of local dof 0, `field_dofs` {field: its local dofs, ghosts included}, `field_owned` {field: its owned ones}."""

    def __init__(self, W: fem.FunctionSpace, field_names: list):
        self.W, self.field_names, self.comm = W, list(field_names), W.mesh.comm
        bs = W.dofmap.index_map_bs
        self.owned_size = W.dofmap.index_map.size_local * bs
        self.offset = W.dofmap.index_map.local_range[0] * bs
        self.field_dofs = {name: np.asarray(W.sub(i).collapse()[1]) for i, name in enumerate(field_names)}
        self.field_owned = {name: dofs[dofs < self.owned_size] for name, dofs in self.field_dofs.items()}

    def sub(self, name: str) -> fem.FunctionSpace:
        """The subspace of W of field `name`."""
        return self.W.sub(self.field_names.index(name))

    def components_owned(self, name: str) -> list:
        """[owned local dofs of component c of vector field `name`] for each component c."""
        sub = self.sub(name)
        parts = [np.asarray(sub.sub(c).collapse()[1]) for c in range(sub.num_sub_spaces)]
        return [dofs[dofs < self.owned_size] for dofs in parts]

    def index_set(self, dofs: np.ndarray) -> PETSc.IS:
        """PETSc IS of the global indices of owned local `dofs`."""
        return PETSc.IS().createGeneral((dofs + self.offset).astype(PETSc.IntType), comm=self.comm)

    def field_is(self, groups: dict) -> list:
        """[(name, PETSc IS of the owned global dofs of its fields)] for {name: [field names]}."""
        return [(name, self.index_set(np.sort(np.concatenate([self.field_owned[f] for f in fields]))))
                for name, fields in groups.items()]

    def split_is(self, splits: dict) -> dict:
        """{name: PETSc IS} of {name: owned local dofs}."""
        return {name: self.index_set(dofs) for name, dofs in splits.items()}

    def owned(self, local_dofs) -> np.ndarray:
        """Sorted owned local dofs marked by `local_dofs` on any process (ghost marks summed to the owner)."""
        marker = fem.Function(self.W)
        marker.x.array[np.asarray(local_dofs, dtype=np.int64)] = 1.0
        vec = marker.vector
        vec.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
        owned = np.flatnonzero(vec.array_r > 0.0).astype(np.int32)
        vec.destroy()           # else kept in its communicator's garbage (fsi.release)
        return owned

    def coupled_splits(self, solid_cells: np.ndarray, pins: list, dirichlet: list) -> dict:
        """Owned local dofs of the splits of the coupled Newton system (linear_solvers.BlockGaussSeidel,
        partitioned.PartitionedCoupling) with the local `solid_cells`, the `pins` and `dirichlet` conditions on W:
        "solid" = velocity and displacement on solid cells (the interface included), the solid pressure, the
        pinned fluid pressures and the Dirichlet rows of the fluid displacement; "mesh" = the other (free) fluid
        mesh displacement; "flow" = the fluid-only velocity and the fluid pressure."""
        collapsed = self.field_dofs
        parts = [fem.locate_dofs_topological(self.sub(f), self.W.mesh.topology.dim, solid_cells)
                 for f in ("velocity", "displacement")]
        parts += [collapsed["solid_pressure"]] if "solid_pressure" in collapsed else []
        parts += [bc.dof_indices()[0] for bc in pins]
        constrained = np.concatenate([np.zeros(0, np.int32)] + [bc.dof_indices()[0] for bc in dirichlet])
        parts.append(np.intersect1d(constrained, collapsed["displacement"]))
        solid = self.owned(np.concatenate(parts))
        mesh = np.setdiff1d(self.owned(collapsed["displacement"]), solid)
        flow = np.setdiff1d(np.arange(self.owned_size, dtype=np.int32), np.union1d(solid, mesh))
        return {"solid": solid, "mesh": mesh, "flow": flow}
