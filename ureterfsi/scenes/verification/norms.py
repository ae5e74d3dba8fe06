"""Error norms and observed orders of convergence of the verification problems, and the integrals and counts
they are made of (SI units)."""
from __future__ import annotations

import math

import numpy as np
import ufl
from dolfinx import fem
from mpi4py import MPI



def observed_order(h, e):
    """Observed orders log(e_k / e_k+1) / log(h_k / h_k+1) between successive refinements
    (h: mesh sizes or time steps, e: errors); an array one shorter than the inputs."""
    h, e = np.asarray(h, dtype=float), np.asarray(e, dtype=float)
    if h.shape != e.shape or h.size < 2:
        raise ValueError("observed_order needs two equally long sequences of at least two values")
    return np.log(e[:-1] / e[1:]) / np.log(h[:-1] / h[1:])


def integrate(expr, mesh, weight=1.0, degree=8, dx=None):
    """Global integral of a UFL expression times `weight` (e.g. 2 pi r in axisymmetric scenes)."""
    measure = dx if dx is not None else ufl.dx(domain=mesh, metadata={"quadrature_degree": degree})
    local = fem.assemble_scalar(fem.form(expr * weight * measure))
    return mesh.comm.allreduce(local, op=MPI.SUM)


def l2_error(uh, exact, weight=1.0, degree=8, mesh=None):
    """(int |uh - exact|^2 weight)^(1/2) and (int |exact|^2 weight)^(1/2); `uh` a Function or a UFL
    expression of one (then give `mesh`), `exact` a UFL expression."""
    mesh = mesh if mesh is not None else uh.function_space.mesh
    diff = uh - exact
    err = integrate(ufl.inner(diff, diff), mesh, weight, degree)
    ref = integrate(ufl.inner(exact, exact), mesh, weight, degree)
    return math.sqrt(max(err, 0.0)), math.sqrt(max(ref, 0.0))


def dofs_count(problem):
    """The global number of unknowns of a problem's mixed space."""
    return problem.W.dofmap.index_map.size_global * problem.W.dofmap.index_map_bs


def mean_facet_value(problem, expr, tag):
    """(int_tag expr dS) / (int_tag dS) over reference facets (no axisymmetric weight)."""
    mesh = problem.mesh
    ds = ufl.Measure("ds", domain=mesh, subdomain_data=problem.scene.facet_tags, metadata={"quadrature_degree": 8})
    return integrate(expr, mesh, dx=ds(tag)) / integrate(fem.Constant(mesh, 1.0), mesh, dx=ds(tag))
