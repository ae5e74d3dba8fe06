"""The peristaltic load's direction (ureterfsi.scenes.ureter.load_direction, config peristalsis.along): on an r-z
wall with a neck (an occlusion's or a stricture's flanks) the normal load pushes each flank along the axis by
p (R(z0) - R(z1)) per radian, the radial load not at all; both put p (z1 - z0) radially on every flank, and on a
straight wall the two are the same vector."""
import numpy as np
import pytest
import ufl
from dolfinx import fem, mesh as dmesh
from mpi4py import MPI

from ureterfsi.scenes.ureter import load_direction

DEPTH, LENGTH, RADIUS, THICKNESS = 0.6, 4.0, 2.0, 0.5


def wall(neck: bool):
    """r-z wall (x[0] = r, x[1] = z) on 0 <= z <= LENGTH, inner radius R(z) = RADIUS - DEPTH sin^2(pi z / LENGTH)
    (a neck at LENGTH / 2) or RADIUS; its outer surface (tag 1) at R(z) + THICKNESS."""
    m = dmesh.create_rectangle(MPI.COMM_WORLD, [np.zeros(2), np.array([1.0, LENGTH])], [4, 64])
    x = m.geometry.x
    inner = RADIUS - (DEPTH * np.sin(np.pi * x[:, 1] / LENGTH) ** 2 if neck else 0.0)
    x[:, 0] = inner + THICKNESS * x[:, 0]
    facets = dmesh.locate_entities_boundary(m, 1, lambda p: np.isclose(p[0] - THICKNESS, RADIUS - (
        DEPTH * np.sin(np.pi * p[1] / LENGTH) ** 2 if neck else 0.0)))
    tags = dmesh.meshtags(m, 1, np.sort(facets), np.ones(len(facets), dtype=np.int32))
    return m, ufl.Measure("ds", domain=m, subdomain_data=tags)


def flank_resultant(along: str, neck: bool, upstream: bool) -> np.ndarray:
    """(radial, axial) resultant of the unit load over the outer surface's upstream (z < L/2) or downstream half."""
    m, ds = wall(neck)
    d = load_direction({"direction": "outward", "along": along}, ufl.FacetNormal(m), axial_component=1)
    z = ufl.SpatialCoordinate(m)[1]
    half = ufl.conditional(ufl.lt(z, LENGTH / 2), 1.0, 0.0) if upstream else ufl.conditional(
        ufl.ge(z, LENGTH / 2), 1.0, 0.0)
    return np.array([m.comm.allreduce(fem.assemble_scalar(fem.form(half * d[i] * ds(1))), op=MPI.SUM)
                     for i in (0, 1)])


@pytest.mark.parametrize("upstream", [True, False])
def test_radial_load_leaves_the_flanks_without_an_axial_push(upstream):
    normal, radial = (flank_resultant(a, True, upstream) for a in ("normal", "radial"))
    sign = 1.0 if upstream else -1.0
    # the outward normal of the narrowing flank points downstream (z1 - z0 = L/2, R falls by DEPTH), of the
    # widening one upstream: the normal load pushes both onto the neck
    assert normal[1] == pytest.approx(sign * DEPTH, rel=1e-12)
    assert abs(radial[1]) < 1e-14
    assert normal[0] == pytest.approx(LENGTH / 2, rel=1e-12)
    assert radial[0] == pytest.approx(LENGTH / 2, rel=1e-12)


def test_both_directions_agree_on_a_straight_wall():
    m, ds = wall(neck=False)
    n = ufl.FacetNormal(m)
    d = {a: load_direction({"direction": "inward", "along": a}, n, axial_component=1) for a in ("normal", "radial")}
    gap = fem.assemble_scalar(fem.form(ufl.inner(d["normal"] - d["radial"], d["normal"] - d["radial"]) * ds(1)))
    assert fem.assemble_scalar(fem.form(d["radial"][0] * ds(1))) == pytest.approx(-LENGTH, rel=1e-12)
    assert abs(gap) < 1e-28
