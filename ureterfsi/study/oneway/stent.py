"""Step 3 of the one-way rung: the stent, quasi-static linear elastic under the urine's interface forces."""
from __future__ import annotations

import time as _time

import numpy as np
import ufl
from dolfinx import fem
from dolfinx.fem import petsc as fem_petsc
from petsc4py import PETSc

from ureterfsi.mesh import tags
from ureterfsi.fsi import physics
from ureterfsi.fsi.operators import Operators
from ureterfsi.fsi.constraints import dirichlet_bcs
from ureterfsi.fsi.problem import MonolithicFSI
from ureterfsi.fsi.scene import DirichletCondition
from ureterfsi.fsi.submesh import SubDomain
from ureterfsi.fsi.probes import CellField, PointProbe, von_mises


class QuasiStaticStent:
    """Linear elastic stent under the urine's interface forces, K u = f(t), K factorised once.

    f at the fluid-stent interface nodes is minus the fluid residual at the interface velocity dofs
    (the consistent reaction: the force the urine exerts on the stent, paper eqs. 22-24); the
    interface nodes of the two submeshes coincide (conforming parent mesh, P2 on both sides)."""

    def __init__(self, stent: SubDomain, material, fluid_pb: MonolithicFSI, symmetric_planes: bool,
                 probe_points: np.ndarray):
        if material.kinematics != "linear":
            raise ValueError("the one-way stent is linear elastic (stent.kinematics: linear)")
        msh = stent.mesh
        self.mesh, self.fluid = msh, fluid_pb
        self.ops = ops = Operators(msh, False)
        V = fem.VectorFunctionSpace(msh, ("Lagrange", fluid_pb.options.velocity_degree))
        self.V = V
        self.u = fem.Function(V, name="stent_displacement")
        dx = ufl.Measure("dx", domain=msh, metadata={"quadrature_degree": fluid_pb.options.quadrature_degree})
        a = physics.elastic_residual(ops, material, ufl.TrialFunction(V), ufl.TestFunction(V), dx)
        # fixed end faces (paper eq. 20) and the mirror planes of the half / quarter models
        conditions = [DirichletCondition("displacement", [tags.STENT_ENDS])]
        if symmetric_planes:
            conditions += [DirichletCondition("displacement", [tag], components=[comp])
                           for tag, comp in ((tags.SYMMETRY_X, 0), (tags.SYMMETRY_Y, 1))]
        self.bcs = bcs = [bc for cond in conditions for bc, _, _ in dirichlet_bcs(cond, V, stent.facet_tags)]
        A = fem_petsc.assemble_matrix(fem.form(a), bcs=bcs)
        A.assemble()
        self.ksp = ksp = PETSc.KSP().create(msh.comm)
        ksp.setOperators(A)
        ksp.setType("preonly")
        ksp.getPC().setType("lu")
        # the stent is small: always a direct factorisation, kept for the whole run
        direct = fluid_pb.options.linear_solver
        ksp.getPC().setFactorSolverType("mumps" if direct == "fieldsplit" else direct)
        self.f = self.u.vector.duplicate()
        self._match_interface(stent)
        self.von_mises = CellField(msh, von_mises(physics.elastic_first_piola(ops, material, self.u)), 1)
        self.probe = PointProbe(msh, probe_points)
        self.residual = fem_petsc.create_vector(fluid_pb.residual_form)
        self.wall_time = 0.0

    def _match_interface(self, stent: SubDomain):
        """Pairs (fluid velocity dof, stent displacement dof) of the interface nodes, by coordinates."""
        pb = self.fluid
        fdim = self.mesh.topology.dim - 1
        Vf, vmap = pb.sub("velocity").collapse()
        vmap = np.asarray(vmap).reshape(-1, 3)
        f_nodes = fem.locate_dofs_topological(Vf, fdim, pb.scene.facet_tags.find(tags.FLUID_STENT))
        s_nodes = fem.locate_dofs_topological(self.V, fdim, stent.facet_tags.find(tags.FLUID_STENT))
        xf = Vf.tabulate_dof_coordinates()[f_nodes]
        xs = self.V.tabulate_dof_coordinates()[s_nodes]
        scale = 1e-9 * max(np.abs(xs).max(), 1e-300)
        key = {tuple(np.round(p / scale).astype(np.int64)): n for p, n in zip(xs, s_nodes)}
        pairs = [(fn, key.get(tuple(np.round(p / scale).astype(np.int64)))) for p, fn in zip(xf, f_nodes)]
        missing = sum(1 for _, sn in pairs if sn is None)
        if missing or len(pairs) != len(s_nodes):
            raise RuntimeError(f"fluid-stent interface nodes do not match ({missing} of {len(pairs)} unpaired, "
                               f"{len(s_nodes)} on the stent side)")
        self.fluid_dofs = vmap[[fn for fn, _ in pairs]]                      # (n, 3) dofs of the mixed space
        self.stent_dofs = 3 * np.array([sn for _, sn in pairs])[:, None] + np.arange(3)

    def update(self, pb: MonolithicFSI) -> None:
        """Solve for the stent displacement under the current urine state; refresh the stress."""
        t0 = _time.perf_counter()
        r = self.residual
        pb.assemble_reaction(r)
        f = self.f
        with f.localForm() as loc:
            loc.set(0.0)
        f.array_w[self.stent_dofs.ravel()] = -r.array_r[self.fluid_dofs.ravel()]
        fem_petsc.set_bc(f, self.bcs)
        self.ksp.solve(f, self.u.vector)
        self.u.x.scatter_forward()
        self.von_mises.update()
        self.wall_time += _time.perf_counter() - t0
