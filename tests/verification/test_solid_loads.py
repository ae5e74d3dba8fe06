"""Body forces and follower pressures on solids, verified against exact solutions.

1. linear elastic bar (nu = 0) hanging under its own weight, 3D and axisymmetric: the exact solution is
   quadratic, so P2 reproduces it to solver tolerance;
2. five-parameter Mooney-Rivlin column in a frictionless channel under its own weight (uniaxial strain, exact
   by quadrature): observed order at large strain, and the O(load^2) deviation from the linear solution;
3. thick incompressible Mooney-Rivlin tube inflated by a follower pressure, plane strain in the r-z mode:
   inner radius against the exact inflation, observed order under refinement, the O(mu/kappa) error of the
   finite bulk modulus, the dead load of the same magnitude (measurably different), the 2D Cartesian and 3D
   paths.
"""
from __future__ import annotations

import dataclasses
import math
import time

import numpy as np
import pytest
import ufl

from ureterfsi.scenes import verification as V
from ureterfsi.fsi import (BodyForce, FollowerPressure, LinearElastic, MonolithicFSI, MooneyRivlin, Scene,
                           SolverOptions)

TIGHT = SolverOptions(newton_rtol=1e-11, newton_atol=1e-13)


# ------------------------------------------------------------------------------------------------
# scene validation
# ------------------------------------------------------------------------------------------------
def test_scene_refuses_misplaced_loads():
    sc = V.hanging_bar_scene(LinearElastic(1e5, 0.0, 1000.0), 1.0)
    with pytest.raises(ValueError, match="BodyForce.tags"):
        Scene(mesh=sc.mesh, cell_tags=sc.cell_tags, facet_tags=sc.facet_tags, solids=sc.solids,
              body_forces=[BodyForce([7], lambda X, t: ufl.as_vector([0.0, 0.0, 1.0]))])
    with pytest.raises(TypeError, match="pressure_loads"):
        Scene(mesh=sc.mesh, cell_tags=sc.cell_tags, facet_tags=sc.facet_tags, solids=sc.solids,
              pressure_loads=[BodyForce([1], lambda X, t: ufl.as_vector([0.0, 0.0, 1.0]))])
    FollowerPressure([1], lambda X, t: 1.0)


# ------------------------------------------------------------------------------------------------
# 1. hanging bar, linear elastic, nu = 0
# ------------------------------------------------------------------------------------------------
@pytest.mark.parametrize("axisymmetric", [False, True], ids=["3d", "axisymmetric"])
def test_hanging_bar_linear_exact(axisymmetric):
    mat = LinearElastic(youngs_modulus=1.0e5, poisson_ratio=0.0, density=1000.0)
    weight, length = 1000.0 * 9.81 * 10.0, 10e-3        # rho g at 10 g: 4.9e-3 tip strain
    pb = MonolithicFSI(V.hanging_bar_scene(mat, weight, axisymmetric, length=length), TIGHT)
    pb.solve_steady()
    X = ufl.SpatialCoordinate(pb.mesh)
    uz = V.hanging_bar_displacement(X[pb.mesh.geometry.dim - 1], length, weight, mat.youngs_modulus)
    exact = ufl.as_vector([0.0, uz] if axisymmetric else [0.0, 0.0, uz])
    err, ref = V.l2_error(pb.field("displacement"), exact, weight=2.0 * math.pi * X[0] if axisymmetric else 1.0)
    print(f"\n[hanging bar, {'r-z' if axisymmetric else '3D'}, P2] relative L2 error {err / ref:.1e}, "
          f"tip u_z {V.hanging_bar_displacement(length, length, weight, mat.youngs_modulus):.4e} m")
    assert ref > 0.0 and err / ref < 1e-10


# ------------------------------------------------------------------------------------------------
# 2. Mooney-Rivlin column in a frictionless channel (uniaxial strain)
# ------------------------------------------------------------------------------------------------
COLUMN = dataclasses.replace(V.URETER_WALL, bulk_modulus=5.0e5)   # compressible: the column deforms
COLUMN_LENGTH = 10e-3


def column_top(weight, n):
    pb = MonolithicFSI(V.confined_column_scene(COLUMN, weight, n, length=COLUMN_LENGTH), TIGHT)
    pb.solve_steady()
    return V.mean_facet_value(pb, pb.field("displacement")[1], 3)


@pytest.mark.parametrize("weight", [2.0e7, 2.0e6], ids=["14%-strain", "1.4%-strain"])
def test_mooney_rivlin_column_order(weight):
    """Top displacement against the exact uniaxial-strain column (N/m^3 `weight`); the coarse meshes are
    pre-asymptotic at large strain, the last orders are 2 (P2 displacement, P0 pressure)."""
    t0 = time.perf_counter()
    exact = V.confined_column_top_displacement(COLUMN_LENGTH, weight, COLUMN)
    ns = (4, 8, 16, 32, 64, 128)
    errs = [abs(column_top(weight, n) - exact) / exact for n in ns]
    orders = V.observed_order([1.0 / n for n in ns], errs)
    print(f"\n[MR column under own weight, top u = {exact * 1e3:.5f} mm ({exact / COLUMN_LENGTH:.1%} mean strain)] "
          f"relative errors {', '.join(f'{e:.2e}' for e in errs)}, orders {', '.join(f'{o:.2f}' for o in orders)}, "
          f"{time.perf_counter() - t0:.1f} s")
    assert exact / COLUMN_LENGTH > 0.01
    assert errs[-1] < 2e-6
    assert np.all(orders > 1.5) and np.all(orders[-2:] > 1.9)


def test_mooney_rivlin_column_small_load_is_linear():
    """u_MR(b) - u_lin(b) = O(b^2): the deviation falls 4x when the load halves. u_lin = b L^2 / (2 M), the
    uniaxial-strain modulus M = kappa + 4 mu/3, mu = 2 (C10 + C01)."""
    modulus = COLUMN.bulk_modulus + 4.0 * COLUMN.shear_modulus / 3.0
    loads = (4e5, 2e5, 1e5, 5e4)
    dev = [column_top(b, 8) - b * COLUMN_LENGTH**2 / (2.0 * modulus) for b in loads]
    ratios = [dev[i] / dev[i + 1] for i in range(len(dev) - 1)]
    print(f"\n[MR column, small loads {loads} N/m^3] deviation from linear {', '.join(f'{d:.3e}' for d in dev)} m, "
          f"ratios {', '.join(f'{r:.3f}' for r in ratios)}")
    assert np.all(np.abs(np.array(ratios) - 4.0) < 0.15)


# ------------------------------------------------------------------------------------------------
# 3. thick-walled Mooney-Rivlin tube under a follower pressure
# ------------------------------------------------------------------------------------------------
INCOMPRESSIBLE = MooneyRivlin(c10=6.0e4, c01=2.0e4, bulk_modulus=1.0e14)   # mu/kappa = 1.6e-9
LOAD_STEPS = 4


def inflate(tube, n, p, follower=True):
    """(inner radius, Newton iterations per load step) of the r-z tube, p ramped in LOAD_STEPS steps."""
    pb = MonolithicFSI(V.tube_axisymmetric_scene(tube, n, lambda t: p * t, follower), TIGHT)
    its = [pb.solve_steady(k / LOAD_STEPS)[0] for k in range(1, LOAD_STEPS + 1)]
    return tube.Ri + V.mean_facet_value(pb, pb.field("displacement")[0], 1), its


@pytest.mark.parametrize("p", [1.0e4, 2.0e4, 3.0e4])
def test_follower_pressure_tube_inflation_order(p):
    t0 = time.perf_counter()
    tube = V.Tube(material=INCOMPRESSIBLE)
    exact = V.mooney_rivlin_tube_inner_radius(tube.Ri, tube.Ro, tube.material, pressure=p)
    ns = (2, 4, 8, 16, 32)
    rows = [inflate(tube, n, p) for n in ns]
    errs = [abs(ri - exact) / (exact - tube.Ri) for ri, _ in rows]
    orders = V.observed_order([1.0 / n for n in ns], errs)
    print(f"\n[follower pressure {p:.0e} Pa, r-z, exact r_i = {exact * 1e3:.5f} mm, hoop strain "
          f"{exact / tube.Ri - 1.0:.1%}] errors of the displacement {', '.join(f'{e:.2e}' for e in errs)}, orders "
          f"{', '.join(f'{o:.2f}' for o in orders)}, Newton its {[its for _, its in rows]}, "
          f"{time.perf_counter() - t0:.1f} s")
    assert np.all(orders > 1.9)
    assert errs[-1] < 2e-5
    assert max(max(its) for _, its in rows) <= 6     # quadratic Newton: the follower term is in the Jacobian


def test_follower_pressure_differs_from_dead_load():
    """The same magnitude as a dead load (P N = -p N) inflates less (r_i p = p0 R_i per unit angle); both
    match their own exact solutions, and the gap is many times the error."""
    tube = V.Tube(material=INCOMPRESSIBLE)
    p = 3.0e4
    follow, _ = inflate(tube, 8, p)
    dead, _ = inflate(tube, 8, p, follower=False)
    exact_f = V.mooney_rivlin_tube_inner_radius(tube.Ri, tube.Ro, tube.material, pressure=p)
    exact_d = V.mooney_rivlin_tube_inner_radius(tube.Ri, tube.Ro, tube.material, dead_load=p)
    print(f"\n[p = {p:.0e} Pa] follower r_i = {follow * 1e3:.5f} mm (exact {exact_f * 1e3:.5f}), dead "
          f"{dead * 1e3:.5f} mm (exact {exact_d * 1e3:.5f}): {(follow - dead) / (dead - tube.Ri):.0%} more "
          "displacement")
    assert abs(follow - exact_f) < 1e-4 * (exact_f - tube.Ri)
    assert abs(dead - exact_d) < 1e-4 * (exact_d - tube.Ri)
    assert follow - dead > 0.5 * (dead - tube.Ri)


def test_follower_pressure_near_incompressibility_error():
    """At fixed mesh the finite bulk modulus shifts r_i by O(mu/kappa): 10x per decade of kappa."""
    p, n = 2.0e4, 16
    radius = {k: inflate(V.Tube(material=dataclasses.replace(INCOMPRESSIBLE, bulk_modulus=k)), n, p)[0]
              for k in (1e9, 1e10, 1e11, 1e14)}
    tube = V.Tube(material=INCOMPRESSIBLE)
    u = radius[1e14] - tube.Ri
    shift = {k: abs(radius[k] - radius[1e14]) / u for k in (1e9, 1e10, 1e11)}
    ratios = [shift[1e9] / shift[1e10], shift[1e10] / shift[1e11]]
    mu = INCOMPRESSIBLE.shear_modulus
    print(f"\n[kappa sweep, p = {p:.0e} Pa, n = {n}] relative shift of u_i: "
          + ", ".join(f"kappa {k:.0e}: {s:.2e} ({s / (mu / k):.2f} mu/kappa)" for k, s in shift.items())
          + f"; ratios {ratios[0]:.2f}, {ratios[1]:.2f}")
    assert all(abs(r - 10.0) < 0.5 for r in ratios)


def test_follower_pressure_plane_strain_cartesian():
    """The quarter annulus (2D Cartesian path, curved P2 geometry) under the follower pressure, the study's
    five-parameter wall (kappa = 1e9): inner radius against the exact inflation."""
    tube = V.Tube()
    p = 2.0e4
    pb = MonolithicFSI(V.tube_scene(tube, 0.5e-3, p, ramp=lambda t: t, follower=True), TIGHT)
    for k in range(1, LOAD_STEPS + 1):
        pb.solve_steady(k / LOAD_STEPS)
    ri = V.tube_inner_radius(pb, tube)
    exact = V.mooney_rivlin_tube_inner_radius(tube.Ri, tube.Ro, tube.material, pressure=p)
    exact_dead = V.mooney_rivlin_tube_inner_radius(tube.Ri, tube.Ro, tube.material, dead_load=p)
    err = abs(ri - exact) / (exact - tube.Ri)
    print(f"\n[follower pressure, plane strain, h = 0.5 mm] r_i = {ri * 1e3:.5f} mm, exact {exact * 1e3:.5f} "
          f"(dead load: {exact_dead * 1e3:.5f}), error {err:.1e} of the displacement")
    assert err < 1e-3
    assert abs(ri - exact_dead) > 100 * abs(ri - exact)


def test_follower_pressure_tube_3d():
    """The quarter tube extruded into one layer of tetrahedra (3D path), u_z = 0 on both ends."""
    t0 = time.perf_counter()
    tube = V.Tube(material=INCOMPRESSIBLE)
    p = 2.0e4
    pb = MonolithicFSI(V.quarter_tube_3d_scene(tube, 0.5e-3, lambda t: p * t), TIGHT)
    its = [pb.solve_steady(k / LOAD_STEPS)[0] for k in range(1, LOAD_STEPS + 1)]
    x = ufl.SpatialCoordinate(pb.mesh) + pb.field("displacement")
    ri = V.mean_facet_value(pb, ufl.sqrt(x[0] ** 2 + x[1] ** 2), 1)
    exact = V.mooney_rivlin_tube_inner_radius(tube.Ri, tube.Ro, tube.material, pressure=p)
    err = abs(ri - exact) / (exact - tube.Ri)
    print(f"\n[follower pressure {p:.0e} Pa, 3D, h = 0.5 mm, {V.dofs_count(pb)} dofs] r_i = {ri * 1e3:.5f} mm, "
          f"exact {exact * 1e3:.5f}, error {err:.1e} of the displacement, Newton its {its}, "
          f"{time.perf_counter() - t0:.1f} s")
    assert err < 1e-4
    assert max(its) <= 6


# ------------------------------------------------------------------------------------------------
# the stability matrix's energy budget counts the new loads
# ------------------------------------------------------------------------------------------------
def test_stability_load_power_counts_body_forces_and_follower_pressures():
    """P_load = int_wall b . v dA + int_outer (-p n) . v ds at a uniform velocity v = (c, c) on the undeformed
    plane channel (wall 4 mm x 1 mm, outer surface 4 mm long, n = (0, 1))."""
    from ureterfsi.fsi.probes import assemble_scalar
    from ureterfsi.stability.observer import StabilityObserver

    b, p, c = (2.0e3, 3.0e3), 100.0, 0.5
    sc = V.channel_scene()
    sc.body_forces.append(BodyForce([2], lambda X, t: ufl.as_vector(b)))
    sc.pressure_loads.append(FollowerPressure([5], lambda X, t: p))
    pb = MonolithicFSI(sc)
    pb.fill("velocity", c)
    obs = StabilityObserver(pb, {"energy_safety": 10.0, "max_wall_time": 60.0})
    exact = (b[0] + b[1]) * c * 4e-3 * 1e-3 - p * c * 4e-3
    assert math.isclose(assemble_scalar(obs.forms["load_power"], pb.comm), exact, rel_tol=1e-12)
