"""Meshes of the stented ureter (paper §2.1, Table 1, §2.4.1): volumes, hole channels, tags, resolution."""
import copy
import hashlib
import json
import math

import numpy as np
import pytest
from mpi4py import MPI

from ureterfsi.mesh import tags
from ureterfsi.config import load_config
from ureterfsi.mesh.geometry import StentModel, UreterGeometry, hole_pair_positions
from ureterfsi.mesh.build import build_mesh
from ureterfsi.mesh.io import load_mesh
from ureterfsi.mesh.io import read_msh

CASES = [("1", "quarter"), ("2", "quarter"), ("3", "quarter"), ("4", "quarter"), ("4", "half"), ("4", "full"),
         ("1", "axisymmetric")]
STENTED = [c for c in CASES if c[0] != "1"]


@pytest.fixture(scope="module")
def cfg():
    return load_config()


@pytest.fixture(scope="module")
def geom(cfg):
    return UreterGeometry.from_config(cfg)


@pytest.fixture(scope="module")
def built(cfg, tmp_path_factory):
    """Coarse meshes built once per case: (msh path, sidecar dict, (mesh, cell_tags, facet_tags))."""
    root, cache = tmp_path_factory.mktemp("meshes"), {}

    def get(model, symmetry):
        if (model, symmetry) not in cache:
            msh, side = root / f"{symmetry}_model{model}.msh", root / f"{symmetry}_model{model}.json"
            build_mesh(cfg, model, "coarse", symmetry, msh, side)
            cache[model, symmetry] = (msh, json.loads(side.read_text()), load_mesh(msh, MPI.COMM_WORLD))
        return cache[model, symmetry]
    return get


def _cell_tag_array(mesh, ct):
    n = mesh.topology.index_map(mesh.topology.dim).size_local
    out = np.zeros(n, dtype=np.int32)
    out[ct.indices] = ct.values
    return out


@pytest.mark.parametrize("model,symmetry", [("1", "axisymmetric"), ("3", "quarter")])
def test_read_msh_agrees_with_gmsh(built, tmp_path, model, symmetry):
    """ureterfsi.mesh.io.read_msh: every physical group's nodes, simplices and name as gmsh's own API gives
    them, the counts of the mesh's sidecar; a truncated file is refused."""
    import gmsh

    from ureterfsi.data.checked import BadFile

    msh, info, _ = built(model, symmetry)
    m = read_msh(msh)
    assert m.dim == (2 if symmetry == "axisymmetric" else 3)
    assert sum(len(c) for c in m.cells().values()) == info["cells_total"]
    assert len(np.unique(np.concatenate([c.ravel() for c in m.cells().values()]))) == info["nodes"]
    assert {tags.FACET_NAMES[t]: len(m.elements(m.dim - 1, t)) for (d, t) in m.groups if d == m.dim - 1} \
        == info["facet_tags"]
    gmsh.initialize()
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.merge(str(msh))
        groups = gmsh.model.getPhysicalGroups()
        assert sorted(m.groups) == sorted(groups)
        for d, t in groups:
            node_tags, xyz = gmsh.model.mesh.getNodesForPhysicalGroup(d, t)
            order = np.argsort(node_tags)
            np.testing.assert_array_equal(m.nodes(d, t), np.asarray(xyz).reshape(-1, 3)[order])
            n_elements = sum(len(e) for ent in gmsh.model.getEntitiesForPhysicalGroup(d, t)
                             for e in gmsh.model.mesh.getElements(d, ent)[1])
            assert len(m.elements(d, t)) == n_elements and m.names[d, t] == gmsh.model.getPhysicalName(d, t)
        some = gmsh.model.mesh.getNodes()[0][::97]
        np.testing.assert_array_equal(m.coords[some.astype(np.int64) - 1],
                                      np.array([gmsh.model.mesh.getNode(int(n))[0] for n in some]))
    finally:
        gmsh.finalize()
    assert m.elements(2, 999).shape == (0, 3)
    cut = tmp_path / "cut.msh"
    cut.write_bytes(msh.read_bytes()[: msh.stat().st_size // 2])
    with pytest.raises(BadFile, match="truncated"):
        read_msh(cut)


@pytest.mark.parametrize("model,symmetry", CASES)
def test_volumes_match_analytic(built, model, symmetry):
    import ufl
    from dolfinx import fem

    msh, info, (mesh, ct, _) = built(model, symmetry)
    assert msh.read_text().startswith("$MeshFormat\n4.1 ")
    dx = ufl.Measure("dx", domain=mesh, subdomain_data=ct)
    one = fem.Constant(mesh, 1.0)
    for name, m in info["subdomain_measure"].items():
        if m["analytic"] == 0.0:
            assert name not in info["cells"] and m["mesh"] == 0.0
            continue
        assert abs(m["rel_error"]) < 5e-3, (name, m)
        tag = {v: k for k, v in tags.CELL_NAMES.items()}[name]
        assembled = fem.assemble_scalar(fem.form(one * dx(tag)))
        assert assembled == pytest.approx(m["mesh"], rel=1e-9)
    assert info["cells_total"] == sum(info["cells"].values()) == ct.values.size


@pytest.mark.parametrize("model,symmetry", STENTED)
def test_hole_channels(cfg, geom, built, model, symmetry):
    from dolfinx import geometry

    _, info, (mesh, ct, _) = built(model, symmetry)
    z = hole_pair_positions(geom, StentModel.from_config(cfg, model))
    signs = (1,) if symmetry == "quarter" else (-1, 1)
    assert info["hole_pair_z"] == pytest.approx(list(z))
    assert info["hole_channels_found"] == len(z) * len(signs)
    assert {c["axis"] for c in info["hole_channels"]} == {"y"}
    found = sorted((c["sign"], c["z"]) for c in info["hole_channels"])
    expected = sorted((s, zk) for s in signs for zk in z)
    assert [s for s, _ in found] == [s for s, _ in expected]
    assert [zc for _, zc in found] == pytest.approx([zk for _, zk in expected], abs=0.1 * geom.hole_radius)
    # probes: fluid at every hole centre (just off the x = 0 plane), stent wall next to it
    rm, a, x0 = geom.probe_radius, geom.hole_radius, 0.2 * geom.hole_radius
    pts = np.array([[x0, s * rm, zk + dz] for s in signs for zk in z for dz in (0.0, 3 * a)])
    tree = geometry.BoundingBoxTree(mesh, mesh.topology.dim)
    cells = geometry.compute_colliding_cells(mesh, geometry.compute_collisions(tree, pts), pts)
    tag_of = _cell_tag_array(mesh, ct)
    got = [tag_of[cells.links(i)[0]] for i in range(len(pts))]
    assert got == [tags.FLUID, tags.STENT] * (len(pts) // 2)


EXPECTED_FACETS = {
    "full": {tags.INLET, tags.OUTLET, tags.URETER_OUTER, tags.URETER_ENDS, tags.STENT_ENDS, tags.FLUID_URETER,
             tags.FLUID_STENT},
    "axisymmetric": {tags.INLET, tags.OUTLET, tags.URETER_OUTER, tags.URETER_ENDS, tags.FLUID_URETER, tags.AXIS},
}
EXPECTED_FACETS["half"] = EXPECTED_FACETS["full"] | {tags.SYMMETRY_X}
EXPECTED_FACETS["quarter"] = EXPECTED_FACETS["half"] | {tags.SYMMETRY_Y}


@pytest.mark.parametrize("model,symmetry", CASES)
def test_every_boundary_and_interface_facet_has_one_tag(geom, built, model, symmetry):
    from dolfinx.mesh import compute_midpoints, exterior_facet_indices

    _, info, (mesh, ct, ft) = built(model, symmetry)
    tdim = mesh.topology.dim
    mesh.topology.create_connectivity(tdim - 1, tdim)
    f2c = mesh.topology.connectivity(tdim - 1, tdim)
    # dolfinx would merge a facet listed in two gmsh groups: compare with the gmsh-side counts
    assert np.unique(ft.indices).size == ft.indices.size == sum(info["facet_tags"].values()), "facet with two tags"
    tagged = dict(zip(ft.indices.tolist(), ft.values.tolist()))
    exterior = exterior_facet_indices(mesh.topology)
    assert all(f in tagged for f in exterior.tolist()), "untagged boundary facet"
    # interior facets: tagged exactly when they separate two subdomains, with the matching interface tag
    tag_of = _cell_tag_array(mesh, ct)
    interface = {frozenset((tags.FLUID, tags.URETER)): tags.FLUID_URETER,
                 frozenset((tags.FLUID, tags.STENT)): tags.FLUID_STENT}
    nf = mesh.topology.index_map(tdim - 1).size_local
    for f in np.setdiff1d(np.arange(nf), exterior):
        pair = frozenset(tag_of[f2c.links(f)].tolist())
        assert tagged.get(f) == interface.get(pair), (f, pair, tagged.get(f))
    expected = EXPECTED_FACETS[symmetry] - ({tags.STENT_ENDS, tags.FLUID_STENT} if model == "1" else set())
    assert set(tagged.values()) == expected
    assert {tags.FACET_NAMES[t] for t in expected} == set(info["facet_tags"])
    # planar tags lie on their planes (axisymmetric: r = x, z = y)
    mid = compute_midpoints(mesh, tdim - 1, ft.indices)
    zc, L, eps = tdim - 1, geom.length, 1e-9
    planes = {tags.INLET: (zc, 0.0), tags.OUTLET: (zc, L), tags.SYMMETRY_X: (0, 0.0), tags.SYMMETRY_Y: (1, 0.0),
              tags.AXIS: (0, 0.0)}
    for t, (axis, value) in planes.items():
        assert np.all(np.abs(mid[ft.values == t, axis] - value) < eps), tags.FACET_NAMES[t]
    for t in (tags.URETER_ENDS, tags.STENT_ENDS):
        d = mid[ft.values == t, zc]
        assert np.all(np.minimum(np.abs(d), np.abs(d - L)) < eps), tags.FACET_NAMES[t]


@pytest.mark.parametrize("model,symmetry", [("3", "quarter"), ("4", "full")])
def test_resolution_across_holes_and_walls(cfg, geom, built, model, symmetry):
    """Coarse level: >= 4 elements across a hole diameter, >= 2 through the stent and ureter walls."""
    _, _, (mesh, ct, _) = built(model, symmetry)
    x = mesh.geometry.x
    a, ro = geom.hole_radius, geom.stent_outer_radius
    r = np.hypot(x[:, 0], x[:, 1])
    tol = 1e-9
    for zk in hole_pair_positions(geom, StentModel.from_config(cfg, model)):
        for s in (-1, 1) if symmetry == "full" else (1,):
            rim = x[(np.abs(r - ro) < tol) & (np.abs(np.hypot(x[:, 0], x[:, 2] - zk) - a) < tol) & (s * x[:, 1] > 0)]
            theta = np.sort(np.arctan2(rim[:, 2] - zk, rim[:, 0]))
            gaps = np.diff(theta) if symmetry != "full" else np.diff(np.r_[theta, theta[0] + 2 * math.pi])
            assert 2 * a * math.sin(gaps.max() / 2) <= 1.02 * (2 * a) / 4, (zk, s, len(rim))
    # a cell touching both surfaces of a wall spans it with one element: must be rare
    dofs = mesh.geometry.dofmap.array.reshape(-1, 4)
    tag_of = _cell_tag_array(mesh, ct)
    for tag, ri, rw in ((tags.STENT, geom.stent_inner_radius, ro),
                        (tags.URETER, geom.ureter_inner_radius, geom.ureter_outer_radius)):
        rc = r[dofs[tag_of == tag]]
        eps = 0.02 * (rw - ri)
        spanning = (np.abs(rc - ri) < eps).any(axis=1) & (np.abs(rc - rw) < eps).any(axis=1)
        assert spanning.mean() < 0.02, (tags.CELL_NAMES[tag], spanning.mean())


def test_mesh_is_deterministic(cfg, built, tmp_path):
    msh, info, _ = built("4", "quarter")
    again = tmp_path / "again.msh"
    build_mesh(cfg, "4", "coarse", "quarter", again, tmp_path / "again.json")
    digest = [hashlib.sha256(p.read_bytes()).hexdigest() for p in (msh, again)]
    assert digest[0] == digest[1]
    assert info["nodes"] == json.loads((tmp_path / "again.json").read_text())["nodes"]


def test_sidecar_records_the_request(cfg, built):
    from ureterfsi.data.provenance import config_hash

    _, info, _ = built("3", "quarter")
    assert (info["model"], info["level"], info["symmetry"], info["size_factor"]) == ("3", "coarse", "quarter", 1.0)
    assert info["config_hash"] == config_hash(cfg)
    assert 0 < info["quality_minSICN"]["min"] <= info["quality_minSICN"]["p01"] <= info["quality_minSICN"]["median"]
    assert info["nodes"] > 0 and info["mesh_wall_time_s"] > 0 and info["gmsh_version"]


@pytest.mark.parametrize("model,level,symmetry,match", [
    ("2", "coarse", "axisymmetric", "not axisymmetric"),
    ("1", "coarse", "eighth", "unknown symmetry"),
    ("1", "ultrafine", "full", "unknown mesh level"),
    ("7", "coarse", "full", "unknown model"),
])
def test_invalid_requests_raise(cfg, tmp_path, model, level, symmetry, match):
    with pytest.raises(ValueError, match=match):
        build_mesh(cfg, model, level, symmetry, tmp_path / "m.msh", tmp_path / "m.json")
    assert not list(tmp_path.iterdir())


@pytest.mark.parametrize("key,value,match", [("hole_pair_spacing", 0.0004, "overlap"), ("holes", 5, "odd")])
def test_invalid_hole_layout_raises(cfg, tmp_path, key, value, match):
    bad = copy.deepcopy(cfg)
    bad["models"]["2"][key] = value
    with pytest.raises(ValueError, match=match):
        build_mesh(bad, "2", "coarse", "quarter", tmp_path / "m.msh", tmp_path / "m.json")


# ------------------------------------------------------------------------------------------ stricture
# the 10 mm segment's coarse meshes as built before the stricture existed (commit 2eb6a24): cells, nodes and the
# first 16 hex digits of the .msh file's SHA-256
UNSTRICTURED = {("3", "quarter"): (13722, 3079, "0b217fb0b7592e08"),
                ("1", "axisymmetric"): (242, 144, "2236c70b11c37d54")}


@pytest.fixture(scope="module")
def mini():
    from ureterfsi.config import load_config_files

    return load_config_files(["config/config.yaml", "config/segment-10mm.yaml"])


@pytest.mark.parametrize("model,symmetry", sorted(UNSTRICTURED))
def test_zero_stricture_gives_todays_mesh(mini, tmp_path, model, symmetry):
    """A zero fraction is no stricture, whatever its length and position: the mesh is today's, node for node."""
    cfg = load_config(mini, {"geometry": {"stricture_fraction": 0.0, "stricture_length": 0.002,
                                          "stricture_position": 0.003}})
    info = build_mesh(cfg, model, "coarse", symmetry, tmp_path / "m.msh", tmp_path / "m.json")
    digest = hashlib.sha256((tmp_path / "m.msh").read_bytes()).hexdigest()[:16]
    assert (info["cells_total"], info["nodes"], digest) == UNSTRICTURED[model, symmetry]


def _interface_nodes(msh, tag: int, dim: int) -> np.ndarray:
    """(r, z) of the nodes of a facet group (r-z section: r = x, z = y)."""
    x = read_msh(msh).nodes(dim - 1, tag)
    return np.c_[x[:, 0], x[:, 1]] if dim == 2 else np.c_[np.hypot(x[:, 0], x[:, 1]), x[:, 2]]


@pytest.mark.parametrize("model,symmetry,fraction", [("1", "axisymmetric", 0.6), ("3", "quarter", 0.7)])
def test_strictured_mesh(mini, tmp_path, model, symmetry, fraction):
    """Wall nodes on R_i(z) (lumen) and R_o(z) (outer surface, constant thickness), the narrowest radius
    exact at the centre, subdomain measures as the profile integrals give, every facet tagged once, the hole mouths
    mesh faces."""
    cfg = load_config(mini, {"geometry": {"stricture_fraction": fraction, "stricture_length": 0.004,
                                          "stricture_position": 0.005}})
    geom, dim = UreterGeometry.from_config(cfg), 2 if symmetry == "axisymmetric" else 3
    info = build_mesh(cfg, model, "coarse", symmetry, tmp_path / "m.msh", tmp_path / "m.json")
    for tag, radius in ((tags.FLUID_URETER, geom.inner_radius), (tags.URETER_OUTER, geom.outer_radius)):
        rz = _interface_nodes(tmp_path / "m.msh", tag, dim)
        assert np.abs(rz[:, 0] - radius(rz[:, 1])).max() < 1e-3 * geom.ureter_inner_radius, tags.FACET_NAMES[tag]
    rz = _interface_nodes(tmp_path / "m.msh", tags.FLUID_URETER, dim)
    assert rz[:, 0].min() == pytest.approx((1 - fraction) * geom.ureter_inner_radius, rel=1e-9)
    assert rz[np.argmin(rz[:, 0]), 1] == pytest.approx(0.005, abs=1e-9)
    for name, m in info["subdomain_measure"].items():
        assert abs(m["rel_error"]) < 5e-3, (name, m)
    assert info["quality_minSICN"]["min"] > 0.1
    if model != "1":
        assert info["hole_channels_found"] == 2
    mesh, ct, ft = load_mesh(tmp_path / "m.msh", MPI.COMM_WORLD)
    assert np.unique(ft.indices).size == ft.indices.size == sum(info["facet_tags"].values())
    expected = EXPECTED_FACETS[symmetry] - ({tags.STENT_ENDS, tags.FLUID_STENT} if model == "1" else set())
    assert set(ft.values.tolist()) == expected
    if model != "1":
        # the hole mouths are faces: no fluid cell crosses the stent's outer radius (the algebraic ALE map's still
        # region ends on faces, ureterfsi.mesh.build._solids)
        x = mesh.geometry.x
        r = np.hypot(x[:, 0], x[:, 1])[mesh.geometry.dofmap.array.reshape(-1, 4)[ct.find(tags.FLUID)]]
        rs, tol = geom.stent_outer_radius, 1e-6 * geom.stent_outer_radius
        inside = r.max(axis=1) <= rs + tol
        assert inside.any() and not np.any(~inside & (r.min(axis=1) < rs - tol))


def test_strictured_wall_model(mini):
    """The r-z wall scene has the same profile: both surfaces moved inward by R_i f b(z), every surface facet
    tagged."""
    from dolfinx.mesh import compute_midpoints

    from ureterfsi.scenes.wall_rz import WallModel

    cfg = load_config(mini, {"geometry": {"stricture_fraction": 0.5, "stricture_length": 0.004,
                                          "stricture_position": 0.005}})
    geom, wall = UreterGeometry.from_config(cfg), WallModel(cfg, nr=4)
    x = wall.problem.mesh.geometry.x
    ft = wall.scene.facet_tags
    assert ft.find(tags.FLUID_URETER).size == ft.find(tags.URETER_OUTER).size == wall.nz
    mesh = wall.problem.mesh
    mesh.topology.create_connectivity(1, 0)
    f2v = mesh.topology.connectivity(1, 0)
    for tag, radius in ((tags.FLUID_URETER, geom.inner_radius), (tags.URETER_OUTER, geom.outer_radius)):
        verts = np.unique(np.concatenate([f2v.links(f) for f in ft.find(tag)]))
        xv = compute_midpoints(mesh, 0, verts.astype(np.int32))
        assert verts.size == wall.nz + 1 and np.abs(xv[:, 0] - radius(xv[:, 1])).max() < 1e-12
    assert x[:, 0].min() == pytest.approx(geom.narrowest_radius, rel=1e-12)


# ------------------------------------------------------------------------------------------ rotated pairs, offset stent


def test_aligned_coaxial_gives_todays_mesh(mini, tmp_path):
    """hole_arrangement aligned with stent_offset 0 is the mesh of before both keys existed, node for node."""
    cfg = load_config(mini, {"geometry": {"hole_arrangement": "aligned", "stent_offset": 0.0}})
    info = build_mesh(cfg, "3", "coarse", "quarter", tmp_path / "m.msh", tmp_path / "m.json")
    digest = hashlib.sha256((tmp_path / "m.msh").read_bytes()).hexdigest()[:16]
    assert (info["cells_total"], info["nodes"], digest) == UNSTRICTURED["3", "quarter"]


@pytest.mark.parametrize("offset,symmetry", [(0.0, "quarter"), (0.001, "half")])
def test_rotated_pairs_mesh(mini, tmp_path, offset, symmetry):
    """rotated_90: pairs on y, x, y (model 2, 3 pairs), found in the mesh's hole channels at their positions. Quarter:
    each hole is cut in half by the plane its axis lies in (its wall spans 0..a across); half y >= 0 with an offset
    stent: the y holes whole (+y side only), the x pair both sides, each cut by y = 0. The stent axis, measured from
    the stent's nodes, lies at the offset; the volumes match the analytic ones."""
    # an offset stent: the study runs the half model (mesh.symmetry; a quarter study with an offset is refused)
    cfg = load_config(mini, {"geometry": {"hole_arrangement": "rotated_90", "stent_offset": offset},
                             "mesh": {"symmetry": symmetry}})
    geom = UreterGeometry.from_config(cfg)
    info = build_mesh(cfg, "2", "coarse", symmetry, tmp_path / "m.msh", tmp_path / "m.json")
    z, a = hole_pair_positions(geom, StentModel.from_config(cfg, "2")), geom.hole_radius
    if symmetry == "quarter":
        expected = [("y", 1, z[0]), ("x", 1, z[1]), ("y", 1, z[2])]
    else:
        expected = [("y", 1, z[0]), ("x", -1, z[1]), ("x", 1, z[1]), ("y", 1, z[2])]
    found = info["hole_channels"]
    assert [(c["axis"], c["sign"]) for c in found] == [(ax, sg) for ax, sg, _ in expected]
    assert [c["z"] for c in found] == pytest.approx([zk for _, _, zk in expected], abs=0.05 * a)
    for c in found:
        cut = symmetry == "quarter" or c["axis"] == "x"
        lo, hi = c["across"]
        assert hi == pytest.approx(a, rel=1e-6) and lo == pytest.approx(0.0 if cut else -a, abs=1e-9), c
    for name, m in info["subdomain_measure"].items():
        assert abs(m["rel_error"]) < 5e-3, (name, m)
    x = read_msh(tmp_path / "m.msh").nodes(3, tags.STENT)     # the stent tube about its axis (offset, 0): r_i <= rho <= r_o
    rho = np.hypot(x[:, 0] - offset, x[:, 1])
    assert rho.max() == pytest.approx(geom.stent_outer_radius, rel=1e-5)     # OCC places nodes within ~1e-9 m
    assert rho.min() == pytest.approx(geom.stent_inner_radius, rel=1e-5) and x[:, 1].min() == pytest.approx(0, abs=1e-12)
    if symmetry == "half":       # the whole x extent: the axis midway
        assert 0.5 * (x[:, 0].min() + x[:, 0].max()) == pytest.approx(offset, abs=1e-8)
    mesh, ct, ft = load_mesh(tmp_path / "m.msh", MPI.COMM_WORLD)
    assert np.unique(ft.indices).size == ft.indices.size == sum(info["facet_tags"].values())
    planes = {"quarter": {tags.SYMMETRY_X, tags.SYMMETRY_Y}, "half": {tags.SYMMETRY_Y}}[symmetry]
    assert set(ft.values.tolist()) == EXPECTED_FACETS["full"] | planes


def test_offset_stent_quarter_refused(mini, tmp_path):
    cfg = load_config(mini, {"geometry": {"stent_offset": 0.001}, "mesh": {"symmetry": "half"}})
    with pytest.raises(ValueError, match=r"^geometry.stent_offset: .*quarter"):
        build_mesh(cfg, "2", "coarse", "quarter", tmp_path / "m.msh", tmp_path / "m.json")
    assert not list(tmp_path.iterdir())
