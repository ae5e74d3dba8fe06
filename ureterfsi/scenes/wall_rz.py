"""The ureter wall alone in the axisymmetric r-z formulation (x = r, y = z): the scene of the calibration
(ureterfsi.study.calibration, paper §2.4.2) and of the wall step of the one-way rung (ureterfsi.study.oneway).

Rectangle [R_i, R_o] x [0, L] (an axisymmetric stricture moves both surfaces inward by R_i f b(z)),
Mooney-Rivlin mixed u-pi, the Gaussian peristaltic dead traction (eq. 21) on the outer surface, on the inner
surface a given urine pressure (a follower pressure) or none, the end faces fixed (eq. 20) or sliding. Tags: the
ureter wall's own (tags.URETER; facets FLUID_URETER inner, URETER_OUTER outer, URETER_ENDS ends).
"""
from __future__ import annotations

import logging
import time as _time

import numpy as np
import ufl
from dolfinx import fem
from dolfinx import mesh as dmesh
from mpi4py import MPI

from ureterfsi.mesh import tags
from ..fsi import (DirichletCondition, FollowerPressure, MonolithicFSI, MooneyRivlin, NewtonDivergence, Scene,
                   SolidRegion, SolverOptions, SurfaceLoad)
from ..fsi.tagging import tag_cells, tag_facets
from ureterfsi.mesh.geometry import Stricture
from .ureter import load_direction, peristaltic_traction, pulse_sigma

log = logging.getLogger("ureterfsi.scenes.wall_rz")


def wall_radii(cfg) -> tuple[float, float]:
    """Reference inner and outer radius (m) of the ureter wall."""
    g = cfg["geometry"]
    Ro = 0.5 * g["ureter_outer_diameter"]
    return Ro - g["ureter_wall_thickness"], Ro


def wall_material(cfg, coefficient_scale=1.0) -> MooneyRivlin:
    """The configured Mooney-Rivlin wall with C10, C01, C20, C02, C11 times coefficient_scale (a float or a
    UFL constant); the bulk modulus unscaled."""
    u = cfg["ureter"]
    s = coefficient_scale
    return MooneyRivlin(s * u["c10"], s * u["c01"], s * u["c20"], s * u["c02"], s * u["c11"],
                        u["bulk_modulus"], u["density"])


class WallModel:
    """Axisymmetric (x = r, y = z) wall-only scene with load and coefficient scales held in UFL constants,
    so a sequence of solves (continuation, calibration) shares one compiled form.

    load: "pulse" (the Gaussian of cfg["peristalsis"]: frozen at a centre for static solves, travelling
    as `ureter.peristaltic_traction` in transient runs) or "uniform" (the peak traction everywhere).
    ends: "fixed" (u = v = 0 at z = 0, L, paper eq. 20) or "sliding" (u_z = v_z = 0 only).
    urine_pressure: p(z, t) (Pa, UFL in the reference z and the time) on the inner surface, following its
    deformation (the one-way rung's assumed urine pressure, scenes.ends.wall_urine_pressure), or None.
    """

    def __init__(self, cfg, nr=4, nz=None, length=None, load="pulse", travelling=False, ends="fixed",
                 options=None, urine_pressure=None):
        if load not in ("pulse", "uniform") or ends not in ("fixed", "sliding"):
            raise ValueError(f"load 'pulse'|'uniform', ends 'fixed'|'sliding'; got {load!r}, {ends!r}")
        self.cfg = cfg
        self.Ri, self.Ro = Ri, Ro = wall_radii(cfg)
        self.length = L = length if length is not None else cfg["geometry"]["length"]
        h = (Ro - Ri) / nr
        nz = nz if nz is not None else max(1, int(round(L / h)))
        self.nr, self.nz = nr, nz
        mesh = dmesh.create_rectangle(MPI.COMM_WORLD, [np.array([Ri, 0.0]), np.array([Ro, L])], (nr, nz),
                                      diagonal=dmesh.DiagonalType.right)
        tol = 1e-9 * L
        ct = tag_cells(mesh, {tags.URETER: lambda x: np.full(x.shape[1], True)})
        ft = tag_facets(mesh, {
            tags.FLUID_URETER: lambda x: np.isclose(x[0], Ri, atol=tol),
            tags.URETER_OUTER: lambda x: np.isclose(x[0], Ro, atol=tol),
            tags.URETER_ENDS: lambda x: np.isclose(x[1], 0.0, atol=tol) | np.isclose(x[1], L, atol=tol)})
        self.stricture = Stricture.from_geometry(cfg["geometry"])
        if self.stricture.fraction > 0:  # tagged straight, then both surfaces moved inward by R_i f b(z)
            mesh.geometry.x[:, 0] += self.stricture.shift(mesh.geometry.x[:, 1], Ri)

        self.load_scale = fem.Constant(mesh, 1.0)
        self.coefficient_scale = fem.Constant(mesh, 1.0)
        self.centre = fem.Constant(mesh, 0.5 * L)
        # the five coefficients as UFL products (scaled without recompiling); kappa stays fixed
        mat = wall_material(cfg, self.coefficient_scale)
        per = cfg["peristalsis"]
        amp, sigma = per["peak_traction"], pulse_sigma(per)
        scale, centre = self.load_scale, self.centre
        self.travelling = travelling and load == "pulse"
        if load == "uniform":
            def traction(X, t, N):
                return scale * amp * load_direction(per, N, 1)
        elif self.travelling:
            moving = peristaltic_traction(per, axial_component=1)

            def traction(X, t, N):
                return scale * moving(X, t, N)
        else:
            def traction(X, t, N):
                return (scale * amp * ufl.exp(-((X[1] - centre) ** 2) / (2.0 * sigma**2))
                        * load_direction(per, N, 1))

        if ends == "fixed":
            dirichlet = [DirichletCondition("displacement", [tags.URETER_ENDS]),
                         DirichletCondition("velocity", [tags.URETER_ENDS])]
        else:
            dirichlet = [DirichletCondition("displacement", [tags.URETER_ENDS], components=[1]),
                         DirichletCondition("velocity", [tags.URETER_ENDS], components=[1])]
        self.scene = Scene(mesh=mesh, cell_tags=ct, facet_tags=ft, solids=[SolidRegion([tags.URETER], mat)],
                           loads=[SurfaceLoad([tags.URETER_OUTER], traction)], dirichlet=dirichlet, axisymmetric=True,
                           pressure_loads=[] if urine_pressure is None else [
                               FollowerPressure([tags.FLUID_URETER], lambda X, t: urine_pressure(X[1], t))],
                           name=f"ureter-wall-rz-{load}-{ends}")
        self.options = options or SolverOptions(newton_rtol=1e-10, newton_atol=1e-12, newton_max_iterations=25)
        t0 = _time.perf_counter()
        self.problem = MonolithicFSI(self.scene, self.options)
        self.setup_time = _time.perf_counter() - t0
        # outer / inner surface nodes of the displacement space (P2: vertices and edge midpoints)
        self._V, self._map = self.problem.sub("displacement").collapse()
        xyz = self._V.tabulate_dof_coordinates()
        self._outer = self.surface_dofs(self._V, tags.URETER_OUTER)
        self._inner = self.surface_dofs(self._V, tags.FLUID_URETER)
        self._z = xyz[:, 1]
        self.comm = mesh.comm
        self.newton_iterations = 0
        # (load scale, coefficient scale, pulse centre) of the current, converged state (x = 0: no load)
        self.state_params = (0.0, 1.0, 0.5 * L)

    def surface_dofs(self, V, facet_tag: int) -> np.ndarray:
        """Owned dofs of a (collapsed) space of this scene on the facets of `facet_tag` (tags.FLUID_URETER:
        inner surface, tags.URETER_OUTER: outer surface), ascending."""
        dofs = fem.locate_dofs_topological(V, 1, self.scene.facet_tags.find(facet_tag))
        return np.unique(dofs[dofs < V.dofmap.index_map.size_local])

    # -------------------------------------------------------------------------------------------
    def mesh_info(self) -> dict:
        pb = self.problem
        tdim = pb.mesh.topology.dim
        return {"cells_r": self.nr, "cells_z": self.nz, "element_size": (self.Ro - self.Ri) / self.nr,
                "cells": self.comm.allreduce(pb.mesh.topology.index_map(tdim).size_local),
                "dofs": pb.W.dofmap.index_map.size_global * pb.W.dofmap.index_map_bs,
                "element": "triangle, P2 velocity/displacement, P0 solid pressure (axisymmetric r-z)",
                "length": self.length}

    def radial_extrema(self):
        """(max u_r on the outer surface, its z, max u_r on the inner surface) of the current state."""
        arr = self.problem.x.x.array[self._map].reshape(-1, 2)
        ur = arr[:, 0]
        best = (-np.inf, 0.0)
        if self._outer.size:
            k = self._outer[np.argmax(ur[self._outer])]
            best = (float(ur[k]), float(self._z[k]))
        inner = float(ur[self._inner].max()) if self._inner.size else -np.inf
        allbest = self.comm.allgather(best)
        umax, z = max(allbest)
        return umax, z, self.comm.allreduce(inner, op=MPI.MAX)

    def _steady(self):
        its, _ = self.problem.solve_steady()
        self.newton_iterations += its
        return its

    def solve_static(self, load_scale=1.0, coefficient_scale=1.0, centre=None, max_halvings=8):
        """Steady solve at the given scales (and frozen pulse centre, m), continued from the current
        converged state; a failing jump is halved along the straight line between the two parameter sets."""
        pb = self.problem
        start = np.array(self.state_params, dtype=float)
        goal = np.array([load_scale, coefficient_scale, start[2] if centre is None else centre], dtype=float)
        consts = (self.load_scale, self.coefficient_scale, self.centre)
        done, frac = 0.0, 1.0
        halvings = 0
        while done < 1.0 - 1e-12:
            trial = min(1.0, done + frac)
            params = start + trial * (goal - start)
            saved = pb.x.x.array.copy()
            for c, v in zip(consts, params):
                c.value = v
            try:
                self._steady()
            except NewtonDivergence:
                pb.x.x.array[:] = saved
                pb.invalidate_jacobian()
                halvings += 1
                if halvings > max_halvings:
                    for c, v in zip(consts, self.state_params):
                        c.value = v
                    raise
                frac *= 0.5
                log.info("static solve: halving the continuation step to %.3g", frac)
                continue
            done = trial
            self.state_params = tuple(float(v) for v in params)
        return self.radial_extrema()
