"""The forms of the partitioned coupling's blocks (fsi.partitioned): each block's rows, their Jacobian in the block's
directions, its matrix on the whole space and the same Jacobian on the block's own fields; the coupling built from
them (partitioned_coupling)."""
from __future__ import annotations


import numpy as np
import ufl
from dolfinx import fem
from dolfinx import mesh as dmesh
from dolfinx.fem import petsc as fem_petsc
from dolfinx.la import ScatterMode

from . import forms, sparsity
from .block_jacobian import BlockJacobian, field_components, field_space
from .partitioned import BlockForms, PartitionedCoupling


def direction(pb, components: dict, fields: dict | None = None):
    """A direction in W for ufl.derivative (or a test function's place in W): {field: its components as a function
    of `fields`} (other fields 0); `fields`: {field: components} of an argument, W's trial function's by default."""
    if fields is None:
        trial, offset, fields = ufl.TrialFunction(pb.W), 0, {}
        for name, element in zip(pb.field_names, pb.W.ufl_element().sub_elements()):
            n = element.value_size()
            fields[name] = [trial[offset + i] for i in range(n)]
            offset += n
    parts = []
    for name in pb.field_names:
        expr = components.get(name)
        size = pb.W.ufl_element().sub_elements()[pb.index[name]].value_size()
        parts += (list(expr(fields)) if expr is not None else [ufl.as_ufl(0.0)] * size)
    return ufl.as_vector(parts)


def direct_jacobian(pb, rows: list, cols: list, jacobian) -> BlockJacobian:
    """The block Jacobian `jacobian`(trial) (a form on W along a direction in W made of `trial`, {field:
    components}) posed on the fields `rows` (test) and `cols` (trial) alone (fsi.block_jacobian).

    The form's own test function is the one replaced, not an equal one built here: ffcx, when it compiles a form,
    gives the mesh's coordinate element another variant (ffcx.analysis._analyze_form), which changes the hash of
    every argument hashed after it, so a new TestFunction(W) would miss the form's in ufl.replace's map, silently."""
    V_rows, row_to_W = field_space(pb.W, pb.field_names, rows)
    V_cols, col_to_W = field_space(pb.W, pb.field_names, cols)
    test = direction(pb, {n: (lambda f, n=n: f[n]) for n in rows},
                     field_components(V_rows, rows, ufl.TestFunction))
    on_W = jacobian(field_components(V_cols, cols, ufl.TrialFunction))
    tests = [a for a in on_W.arguments() if a.number() == 0]
    if len(tests) != 1 or tests[0].ufl_function_space() != pb.W.ufl_function_space():
        raise ValueError(f"the block Jacobian {rows} x {cols} has no test function on the mixed space to replace")
    form = ufl.replace(on_W, {tests[0]: test})
    if any(a.ufl_function_space() == pb.W.ufl_function_space() for a in form.arguments()):
        raise RuntimeError(f"the block Jacobian {rows} x {cols} kept an argument on the mixed space")
    return BlockJacobian(fem.form(form), row_to_W, col_to_W)


def partitioned_coupling(pb, whole, terms) -> "PartitionedCoupling":
    """The partitioned strategy on MonolithicFSI `pb` (a coupled scene, monolithic mesh motion) with the residual's
    terms `whole` and `terms`(dx, ds) (the same terms with other measures). The urine's rows: the residual but the
    solids' volume terms, differentiated in the velocity and pressure directions. The wall's rows (solid_block
    "condensed"): the residual over the solid cells and the urine cells touching them (`terms`(dx) with that
    measure), differentiated along the kinematic direction (dv = (b0/dt) du, du, d pi, dp: fsi.condensation), and the
    solids' mass matrix. The wall's Jacobian integrates with wall_jacobian_quadrature_degree where it is set."""
    own = pb.options.jacobian_sparsity == "couplings"
    R_flow = whole.urine + whole.loads
    flow_fields = {"velocity": lambda f: f["velocity"], "pressure": lambda f: f["pressure"]}
    flow_jacobian = fem.form(ufl.derivative(R_flow, pb.x, direction(pb, flow_fields)))
    flow = BlockForms(fem.form(R_flow), flow_jacobian,
                      sparsity.coupled_matrix(pb.W, pb.field_names, pb.cells(pb.fluid_tags), [], part="flow")
                      if own else fem_petsc.create_matrix(flow_jacobian),
                      direct_jacobian(pb, ["velocity", "pressure"], ["velocity", "pressure"],
                                      lambda trial: ufl.derivative(R_flow, pb.x, direction(pb, flow_fields, trial))))
    splits = pb.layout.coupled_splits(pb.cells(pb.solid_tags), pb.constraints.pins, pb.constraints.dirichlet)
    wall = None
    if pb.options.solid_block == "condensed":
        urine_cells = cells_touching(pb, pb.cells(pb.fluid_tags), splits["solid"])
        wall_cells = np.union1d(pb.cells(pb.solid_tags), urine_cells)
        tags = pb.scene.cell_tags
        keep = np.isin(tags.indices, wall_cells)
        wall_tags = dmesh.meshtags(pb.mesh, pb.mesh.topology.dim, tags.indices[keep], tags.values[keep])
        dxw = ufl.Measure("dx", domain=pb.mesh, subdomain_data=wall_tags, metadata=pb.dx.metadata())
        w = terms(dxw)
        R_wall = w.urine + w.solids + w.loads
        degree = pb.options.wall_jacobian_quadrature_degree
        if degree is not None and int(degree) < 1:
            raise ValueError(f"wall_jacobian_quadrature_degree: an integer >= 1 or None, got {degree!r}")
        if degree is None:
            J_wall = R_wall
        else:
            md = {"quadrature_degree": int(degree)}
            jw = terms(ufl.Measure("dx", domain=pb.mesh, subdomain_data=wall_tags, metadata=md),
                       ufl.Measure("ds", domain=pb.mesh, subdomain_data=pb.ds.subdomain_data(), metadata=md))
            J_wall = jw.urine + jw.solids + jw.loads
        others = {n: (lambda f, n=n: f[n]) for n in ("displacement", "pressure", "solid_pressure")
                  if n in pb.field_names}

        def along_kinematics(trial=None):
            """The wall's Jacobian along dv = (b0/dt) du (trial: {field: components}, W's by default)."""
            velocity = direction(pb, {"velocity": lambda f: f["displacement"]}, trial)
            along = {n: d for n, d in others.items() if trial is None or n in trial}
            return (pb.bdf[0] / pb.dt * ufl.derivative(J_wall, pb.x, velocity)
                    + ufl.derivative(J_wall, pb.x, direction(pb, along, trial)))

        wall_jacobian = fem.form(along_kinematics())
        # the condensed operator's rows and columns: K = J[Q, R] (fsi.condensation); the fluid pressures among
        # them are the pinned ones (identities), so the pressure is neither a row nor a column field
        pi = ["solid_pressure"] if "solid_pressure" in pb.field_names else []
        direct = direct_jacobian(pb, ["velocity"] + pi, ["displacement"] + pi, along_kinematics)
        v_trial = ufl.split(ufl.TrialFunction(pb.W))[pb.index["velocity"]]
        psi = ufl.split(ufl.TestFunction(pb.W))[pb.index["displacement"]]
        mass_form = fem.form(forms.kinematic_mass(pb.ops, pb.scene, v_trial, psi, dxw))
        solid_cells = pb.cells(pb.solid_tags)
        wall = BlockForms(fem.form(R_wall), wall_jacobian,
                          sparsity.coupled_matrix(pb.W, pb.field_names, urine_cells, pb.solid_regions(),
                                                  part="wall"), direct,
                          mass=(mass_form, sparsity.pattern_matrix(
                              pb.W, pb.field_names, [(solid_cells, ["displacement"], ["velocity"])],
                              np.arange(pb.x.vector.getLocalSize(), dtype=np.int32))))
    return PartitionedCoupling(pb, splits, flow, wall, pb.options.block_iterations)


def cells_touching(pb, cells: np.ndarray, dofs: np.ndarray) -> np.ndarray:
    """Those of `cells` (local) with a velocity dof among the owned local `dofs` of any rank."""
    marker = fem.Function(pb.W)
    marker.x.array[dofs] = 1.0
    marker.x.scatter_reverse(ScatterMode.add)
    marker.x.scatter_forward()
    cell_dofs = sparsity.cell_dofs(pb.W, pb.field_names, "velocity")[cells]
    return cells[(marker.x.array[cell_dofs] > 0).any(axis=1)]
