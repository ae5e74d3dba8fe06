"""ureterfsi.fsi.probes against fields with known answers on small dolfinx meshes: point evaluation of a
linear field (exact), von Mises stress of known stress states, location of a cell-field maximum, and
the volumetric flux of a prescribed velocity through a boundary with the study's Nanson-form integrand."""
from __future__ import annotations

import json
import math
import os
import shutil
import subprocess
import sys
from pathlib import Path

import gmsh
import numpy as np
import pytest
import ufl
from dolfinx import fem, mesh as dmesh
from dolfinx.io import gmshio
from mpi4py import MPI

from ureterfsi.fsi.probes import CellField, PointProbe, assemble_scalar, surface_line_points, von_mises

COMM = MPI.COMM_WORLD


@pytest.fixture(scope="module")
def cube():
    return dmesh.create_unit_cube(COMM, 4, 4, 4)


def test_point_probe_linear_field_is_exact(cube):
    V = fem.FunctionSpace(cube, ("CG", 1))
    f = fem.Function(V)
    f.interpolate(lambda x: 1.0 + 2.0 * x[0] - 3.0 * x[1] + 0.5 * x[2])
    W = fem.VectorFunctionSpace(cube, ("CG", 1))
    g = fem.Function(W)
    g.interpolate(lambda x: np.vstack([x[0], -x[1], 2.0 * x[2] + x[0]]))
    rng = np.random.default_rng(1)
    pts = np.vstack([rng.random((20, 3)), [[0.0, 0.0, 0.0], [1.0, 1.0, 1.0], [0.5, 0.5, 0.5], [1.5, 0.5, 0.5]]])
    probe = PointProbe(cube, pts)
    val = probe(f)
    assert val.shape == (len(pts), 1)
    exact = 1.0 + 2.0 * pts[:, 0] - 3.0 * pts[:, 1] + 0.5 * pts[:, 2]
    np.testing.assert_allclose(val[:-1, 0], exact[:-1], atol=1e-12)
    assert np.isnan(val[-1, 0])                                  # outside the mesh
    vec = probe(g)
    np.testing.assert_allclose(vec[:-1], np.c_[pts[:, 0], -pts[:, 1], 2 * pts[:, 2] + pts[:, 0]][:-1], atol=1e-12)


def test_point_probe_accepts_2d_points():
    square = dmesh.create_unit_square(COMM, 3, 3)
    f = fem.Function(fem.FunctionSpace(square, ("CG", 1)))
    f.interpolate(lambda x: 3.0 * x[0] + x[1])
    pts = np.array([[0.2, 0.7], [0.9, 0.1]])
    np.testing.assert_allclose(PointProbe(square, pts)(f)[:, 0], 3 * pts[:, 0] + pts[:, 1], atol=1e-12)



def _cells_holding(msh, point, tol=1e-12):
    """The local cells of a triangle mesh whose closure holds `point` (barycentric coordinates >= -tol)."""
    x, dofmap = msh.geometry.x[:, :2], msh.geometry.dofmap
    found = []
    for c in range(msh.topology.index_map(2).size_local + msh.topology.index_map(2).num_ghosts):
        a, b, d = x[dofmap.links(c)]
        lam = np.linalg.solve(np.c_[b - a, d - a], point - a)
        if min(lam.min(), 1 - lam.sum()) >= -tol:
            found.append(c)
    return found


def test_point_probe_takes_the_mean_of_a_cell_field_over_the_cells_of_a_point():
    """A piecewise-constant field (a different value on each cell) probed inside a cell, on a face, at a vertex:
    the cell's value, the mean of the two, the mean of all the vertex's cells (the brute-force point-in-triangle
    search here); with `within`, the mean over those cells only and NaN in none of them."""
    square = dmesh.create_unit_square(MPI.COMM_SELF, 2, 2)
    f = fem.Function(fem.FunctionSpace(square, ("DG", 0)))
    f.interpolate(lambda x: x[0] + 10.0 * x[1] + 100.0 * x[0] * x[1])      # distinct on every cell
    pts = np.array([[0.2, 0.1], [0.5, 0.25], [0.5, 0.5], [0.25, 0.5], [0.75, 0.75]])
    got = PointProbe(square, pts)(f)[:, 0]
    holding = [_cells_holding(square, p) for p in pts]
    assert [len(h) for h in holding] == [1, 2, 6, 2, 2]                        # a cell, faces, a vertex
    for value, cells in zip(got, holding):
        assert value == pytest.approx(np.mean(f.x.array[cells]), abs=1e-13)
    lower = np.flatnonzero(dmesh.compute_midpoints(square, 2, np.arange(8, dtype=np.int32))[:, 1] < 0.5)
    within = PointProbe(square, pts, within=lower)(f)[:, 0]
    for value, cells in zip(within, holding):
        kept = [c for c in cells if c in lower]
        assert np.isnan(value) if not kept else value == pytest.approx(np.mean(f.x.array[kept]), abs=1e-13)
    assert np.isnan(within[-1]) and not np.isnan(within[1])


_PROBE_DRIVER = """
import json, sys
import numpy as np
from mpi4py import MPI
from dolfinx import fem, mesh as dmesh
sys.path.insert(0, {src!r})
from ureterfsi.fsi.probes import PointProbe
cube = dmesh.create_unit_cube(MPI.COMM_WORLD, 4, 4, 4)
f = fem.Function(fem.FunctionSpace(cube, ("DG", 1)))
f.interpolate(lambda x: np.sin(7 * x[0]) + x[1] * x[2] + np.floor(4 * x[0]))      # jumps across cell faces
z = np.linspace(0.0, 1.0, 41)
pts = np.c_[0.25 + 0 * z, 0.5 + 0 * z, z]                                     # on faces, edges and vertices
pts = np.vstack([pts, [[0.1, 0.2, 0.3], [0.5, 0.5, 0.5], [1.5, 0.5, 0.5]]])
values = PointProbe(cube, pts)(f)[:, 0]
if MPI.COMM_WORLD.rank == 0:
    json.dump([None if np.isnan(v) else float(v) for v in values], open({out!r}, "w"))
"""


@pytest.mark.mpi
@pytest.mark.skipif(shutil.which("mpiexec") is None, reason="mpiexec not installed")
def test_point_probe_values_do_not_depend_on_the_partition(tmp_path):
    """A discontinuous field probed along a line of cell faces, edges and vertices: the same values on 1 and 2
    processes (the first colliding cell of the lowest rank, the rule before the mean, gave the partition's)."""
    results = {}
    for n in (1, 2):
        out = tmp_path / f"np{n}.json"
        script = tmp_path / "driver.py"
        script.write_text(_PROBE_DRIVER.format(src=str(Path(__file__).resolve().parents[2]), out=str(out)))
        proc = subprocess.run(["mpiexec", "-n", str(n), "--allow-run-as-root", "--oversubscribe", sys.executable,
                               str(script)], capture_output=True, text=True, timeout=600,
                              env=dict(os.environ, OMPI_MCA_rmaps_base_oversubscribe="1"))
        assert proc.returncode == 0, proc.stderr[-3000:]
        results[n] = json.loads(out.read_text())
    assert results[1][-1] is None and results[2][-1] is None                  # outside the mesh
    one, two = np.array(results[1][:-1], dtype=float), np.array(results[2][:-1], dtype=float)
    np.testing.assert_allclose(two, one, rtol=0, atol=1e-12 * np.abs(one).max())

@pytest.mark.parametrize("state, expected", [
    ("uniaxial", 7.0),                     # sigma = s e1 (x) e1 -> s
    ("shear", math.sqrt(3.0) * 2.0),       # sigma = t (e1 (x) e2 + e2 (x) e1) -> sqrt(3) t
    ("hydrostatic", 0.0),                  # sigma = p I -> 0
    ("uniaxial_plus_pressure", 7.0),       # invariant to an added pressure
])
def test_von_mises_of_known_stress_states(cube, state, expected):
    # magnitudes as mesh Constants: the expression needs a domain to be interpolated
    s, t, p = (fem.Constant(cube, c) for c in (7.0, 2.0, -5.0))
    I = ufl.Identity(3)
    e1, e2 = ufl.as_vector([1.0, 0.0, 0.0]), ufl.as_vector([0.0, 1.0, 0.0])
    sigma = {"uniaxial": s * ufl.outer(e1, e1), "shear": t * (ufl.outer(e1, e2) + ufl.outer(e2, e1)),
             "hydrostatic": p * I, "uniaxial_plus_pressure": s * ufl.outer(e1, e1) + p * I}[state]
    field = CellField(cube, von_mises(sigma), 1)
    values = field.update().x.array
    np.testing.assert_allclose(values, expected, atol=1e-12)
    assert field.maximum()[0] == pytest.approx(expected, abs=1e-12)


def test_von_mises_of_a_spatially_varying_stress(cube):
    """Uniaxial stress growing linearly in x: von Mises = |s(x)|, maximum at x = 1."""
    x = ufl.SpatialCoordinate(cube)
    e3 = ufl.as_vector([0.0, 0.0, 1.0])
    field = CellField(cube, von_mises((1.0 + 4.0 * x[0]) * ufl.outer(e3, e3)), 1)
    field.update()
    vmax, where = field.maximum()
    assert vmax == pytest.approx(5.0, abs=1e-12) and where[0] == pytest.approx(1.0)


def test_cell_field_maximum_location(cube):
    x = ufl.SpatialCoordinate(cube)
    expr = x[0] + 2.0 * x[1] + 3.0 * x[2]
    field = CellField(cube, expr, 1)
    field.update()
    vmax, where = field.maximum()
    assert vmax == pytest.approx(6.0, abs=1e-12)
    np.testing.assert_allclose(where, [1.0, 1.0, 1.0], atol=1e-12)
    # restricted to the cells with midpoint x < 0.5: maximum on the face x = 0.5 at y = z = 1
    n = cube.topology.index_map(3).size_local
    mid = dmesh.compute_midpoints(cube, 3, np.arange(n, dtype=np.int32))
    sub = CellField(cube, expr, 1, np.flatnonzero(mid[:, 0] < 0.5).astype(np.int32))
    sub.update()
    vmax, where = sub.maximum()
    assert vmax == pytest.approx(5.5, abs=1e-12)
    np.testing.assert_allclose(where, [0.5, 1.0, 1.0], atol=1e-12)


TOP = 12


@pytest.fixture(scope="module")
def cylinder():
    """Unit cylinder r <= 1, 0 <= z <= 1 with the top face z = 1 tagged TOP."""
    gmsh.initialize()
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.model.add("cyl")
        vol = gmsh.model.occ.addCylinder(0, 0, 0, 0, 0, 1, 1.0)
        gmsh.model.occ.synchronize()
        top = [s for _, s in gmsh.model.getBoundary([(3, vol)], oriented=False)
               if abs(gmsh.model.occ.getCenterOfMass(2, s)[2] - 1.0) < 1e-9]
        gmsh.model.addPhysicalGroup(3, [vol], 1)
        gmsh.model.addPhysicalGroup(2, top, TOP)
        gmsh.option.setNumber("Mesh.MeshSizeMax", 0.12)
        gmsh.model.mesh.generate(3)
        msh, _, facets = gmshio.model_to_mesh(gmsh.model, COMM, 0, gdim=3)
    finally:
        gmsh.finalize()
    return msh, facets


@pytest.mark.parametrize("dilation", [0.0, 0.1])
def test_flux_of_poiseuille_profile_through_a_disk(cylinder, dilation):
    """v = (0, 0, 1 - r^2) through the top of the unit cylinder: pi/2 (times (1+a)^2 on a mesh dilated by
    u = a X, through the study's integrand (v - w) . J F^-T N dA with w = 0)."""
    msh, facets = cylinder
    V = fem.VectorFunctionSpace(msh, ("CG", 2))
    v, u = fem.Function(V), fem.Function(V)
    v.interpolate(lambda x: np.vstack([0 * x[0], 0 * x[0], 1.0 - x[0] ** 2 - x[1] ** 2]))
    u.interpolate(lambda x: dilation * x)
    F = ufl.Identity(3) + ufl.grad(u)
    J = ufl.det(F)
    N = ufl.FacetNormal(msh)
    n_da = J * ufl.inv(F).T * N
    ds = ufl.Measure("ds", domain=msh, subdomain_data=facets, metadata={"quadrature_degree": 6})
    flux = assemble_scalar(fem.form(ufl.dot(v, n_da) * ds(TOP)), COMM)
    area = assemble_scalar(fem.form(ufl.sqrt(ufl.dot(n_da, n_da)) * ds(TOP)), COMM)
    e_z = ufl.as_vector([0.0, 0.0, 1.0])
    mean_axial = assemble_scalar(fem.form(ufl.dot(v, e_z) * ufl.sqrt(ufl.dot(n_da, n_da)) * ds(TOP)), COMM) / area
    scale = (1.0 + dilation) ** 2
    # polygonal boundary of the disk: O(h^2) deficit, < 0.5 % at this size
    assert flux == pytest.approx(scale * math.pi / 2, rel=5e-3)
    assert area == pytest.approx(scale * math.pi, rel=5e-3)
    assert mean_axial == pytest.approx(0.5, rel=5e-3)
    # exactness on the meshed (polygonal) disk: the flux equals the integral of 1 - r^2 over the facets
    one = assemble_scalar(fem.form((1.0 - ufl.SpatialCoordinate(msh)[0] ** 2 - ufl.SpatialCoordinate(msh)[1] ** 2)
                                   * ds(TOP)), COMM)
    assert flux == pytest.approx(scale * one, rel=1e-10)


@pytest.mark.parametrize("c", [0.0, 150.0])
def test_end_face_pressure_mean_of_a_prescribed_field(c):
    """ureterfsi.fsi.probes.end_face_pressure_forms on the r-z tube of the engine tests: p = a + b z + e r (P1, exact)
    with the ALE displacement u_r = c r^2 (c = 0: reference faces). The current-area mean on the face z = z_f is
    a + b z_f + e int r r'(r) r''(r) dr / int r'(r) r''(r) dr, r' = r + c r^2 (the current radius), r'' = dr'/dr."""
    from helpers.engine_cases import INLET, LENGTH, OUTLET, R_I, tube_problem
    from ureterfsi.fsi.probes import end_face_pressure_forms

    pb, _ = tube_problem()
    a, b, e = 130.0, -2.5e3, 4.0e4                     # Pa, Pa/m, Pa/m
    for name, expr in (("pressure", lambda x: a + b * x[1] + e * x[0]),
                       ("displacement", lambda x: np.vstack([c * x[0] ** 2, 0.0 * x[0]]))):
        V, dofs = pb.W.sub(pb.index[name]).collapse()
        f = fem.Function(V)
        f.interpolate(expr)
        pb.x.x.array[dofs] = f.x.array
    val = {k: assemble_scalar(fem.form(f), COMM) for k, f in end_face_pressure_forms(pb, INLET, OUTLET).items()}
    weight = np.polynomial.Polynomial([0.0, 1.0, c]) * np.polynomial.Polynomial([1.0, 2.0 * c])   # r' dr'/dr
    r = np.polynomial.Polynomial([0.0, 1.0])
    r_mean = (r * weight).integ()(R_I) / weight.integ()(R_I)
    for end, z in (("inlet", 0.0), ("outlet", LENGTH)):
        assert val[f"{end}_area"] == pytest.approx(math.pi * (R_I + c * R_I**2) ** 2, rel=1e-12)
        assert val[f"{end}_pressure_integral"] / val[f"{end}_area"] == pytest.approx(a + b * z + e * r_mean,
                                                                                      rel=1e-12)


@pytest.mark.parametrize("symmetry,fraction", [("quarter", 0.7), ("half", 0.7), ("full", 0.0), ("axisymmetric", 0.7)])
def test_wall_line_lies_on_the_outer_facets(tmp_path, repo_root, symmetry, fraction):
    """The wall probes' line (surface_line_points: the meridian y = 0, x > 0 on the mesh's own outer facets) on the
    study's 10 mm coarse meshes of the unstented model: a point at every z, on R_o(z) (narrowed by a stricture) to the
    facet chords, and the radial displacement read there is that of an interpolated u = a(z) e_r to the P2
    interpolation error. The straight line x = R_o, y = 0 the fully coupled rung read before lies outside the wall
    under a stricture (NaN, left out of its maximum) and, with no mesh edge on the meridian (the full mesh), everywhere."""
    from ureterfsi.mesh import tags
    from ureterfsi.config import load_config, load_config_files
    from ureterfsi.mesh.geometry import UreterGeometry
    from ureterfsi.mesh.build import build_mesh
    from ureterfsi.mesh.io import load_mesh

    mini = load_config_files([repo_root / "config/config.yaml", repo_root / "config/segment-10mm.yaml"])
    cfg = load_config(mini, {"geometry": {"stricture_fraction": fraction, "stricture_length": 0.004,
                                          "stricture_position": 0.005}})
    geom, axisymmetric = UreterGeometry.from_config(cfg), symmetry == "axisymmetric"
    build_mesh(cfg, "1", "coarse", symmetry, tmp_path / "m.msh", tmp_path / "m.json")
    msh, _, ft = load_mesh(tmp_path / "m.msh", COMM)
    z = np.linspace(0.0, geom.length, 201)
    pts, cells = surface_line_points(msh, ft.find(tags.URETER_OUTER), z, axisymmetric)
    probe = PointProbe(msh, pts[:, :msh.geometry.dim], cells)
    assert probe.missing.size == 0                                # every point on a facet of some rank
    a = lambda zz: 1e-4 * np.exp(-((zz - 0.004) / 0.0015) ** 2)  # noqa: E731  (peak on the stricture's flank)
    u = fem.Function(fem.VectorFunctionSpace(msh, ("CG", 2)))
    if axisymmetric:
        u.interpolate(lambda x: np.vstack([a(x[1]), 0.0 * x[1]]))
    else:
        u.interpolate(lambda x: np.vstack([a(x[2]) * x[0] / np.hypot(x[0], x[1]),
                                           a(x[2]) * x[1] / np.hypot(x[0], x[1]), 0.0 * x[2]]))
    ur = probe(u)[:, 0]
    assert np.abs(ur - a(z)).max() < 2e-3 * a(z).max()           # measured 4e-4 - 1.1e-3
    np.testing.assert_allclose(pts[:, 0], geom.outer_radius(z), rtol=0, atol=0.02 * geom.ureter_inner_radius)
    straight = pts.copy()
    straight[:, 0] = geom.ureter_outer_radius
    straight = PointProbe(msh, straight[:, :msh.geometry.dim])(u)
    lost = np.isnan(straight[:, 0])
    under = geom.radial_shift(z) < -1e-6 * geom.ureter_inner_radius
    assert lost[under].all() and (lost.all() if symmetry == "full" else under.any())
