"""The complete occlusion (ureterfsi.geometry.Occlusion), the positive control of the side holes: geometry and mesh,
refusals, and the fully coupled rung's mass balance and tie on the 10 mm segment (config/occlusion.yaml, model 3,
coarse quarter mesh, two steps of 20 ms).

Discrete mass balance: the continuity rows hold int_Omega J tr(Grad v F^-1) q dX = 0 for every P1 q of the fluid.
With q = 1 at the fluid's vertices upstream of the cut z_o (the occlusion's centre), v - w the velocity relative to the
mesh (w its BDF velocity; v = w on the walls) and cof F = J F^-T, that is, exactly under quadrature of degree >= 5
(the integrands are polynomials), Q_in = Q_cut + S with
  Q_in = -int_inlet q (v - w).cof F N dA, Q_cut = -int cof F Grad q.(v - w) dX (through the layer of cells the cut
  crosses), S = int q tr(Grad w cof F^T) dX (the rate of change of the upstream urine's volume);
so the check holds to the solver's tolerance. At z_o only the stent lumen holds urine, so Q_cut is the lumen's
flux there; with q = 1 on the annulus' vertices (r >= r_s) on one side, Q_cut is the flux through that side's holes.
"""
from __future__ import annotations

import numpy as np
import pytest
import ufl
from dolfinx import fem
from dolfinx.mesh import compute_midpoints
from mpi4py import MPI

from ureterfsi.config import ConfigError, load_config, load_config_files, unmakeable
from ureterfsi.fsi import TimeIntegrator, TimeSettings
from ureterfsi.fsi.integrator import Observer
from ureterfsi.fsi.problem import MonolithicFSI
from ureterfsi.mesh import tags
from ureterfsi.mesh.build import build_mesh
from ureterfsi.mesh.geometry import StentModel, UreterGeometry, hole_pair_positions
from ureterfsi.mesh.io import load_mesh, read_msh
from ureterfsi.scenes.ureter import ureter_scene
from ureterfsi.study import oneway
from ureterfsi.study.options import RunSpec, solver_options

OCCLUSION = {"occlusion_length": 0.001, "occlusion_position": 0.005, "occlusion_taper": 0.0025}


@pytest.fixture(scope="module")
def occluded_cfg(repo_root):
    return load_config_files([repo_root / "config/config.yaml", repo_root / "config/segment-10mm.yaml",
                              repo_root / "config/occlusion.yaml"])


@pytest.fixture(scope="module")
def occluded_mesh(occluded_cfg, tmp_path_factory):
    d = tmp_path_factory.mktemp("occlusion")
    info = build_mesh(occluded_cfg, "3", "coarse", "quarter", d / "model3.msh", d / "model3.json")
    return d / "model3.msh", info


# ---- geometry and mesh ----------------------------------------------------------------------------------------

def test_profile_meets_the_stent_at_an_angle_and_joins_the_wall(occluded_cfg):
    g = UreterGeometry.from_config(occluded_cfg)
    lo, hi = g.occlusion.span
    z0, z1 = g.occlusion.contact
    assert (lo, z0, z1, hi) == pytest.approx((0.002, 0.0045, 0.0055, 0.008))
    assert g.inner_radius(np.array([0.0, lo, z0, 0.005, z1, hi, 0.01])) == pytest.approx(
        [g.ureter_inner_radius, g.ureter_inner_radius, g.stent_outer_radius, g.stent_outer_radius,
         g.stent_outer_radius, g.ureter_inner_radius, g.ureter_inner_radius], abs=1e-15)
    assert g.outer_radius(0.005) == pytest.approx(g.stent_outer_radius + 0.001)
    h = 1e-7   # slope at the contact's edge: (R_i - r_s) pi / (2 t), a finite angle (no cusp of urine)
    slope = (g.inner_radius(z0 - h) - g.inner_radius(z0)) / h
    assert slope == pytest.approx((g.ureter_inner_radius - g.stent_outer_radius) * np.pi / (2 * 0.0025), rel=1e-3)


def test_mesh_ties_the_wall_to_the_stent_and_closes_the_annulus(occluded_cfg, occluded_mesh):
    path, info = occluded_mesh
    g = UreterGeometry.from_config(occluded_cfg)
    m = read_msh(path)
    x = m.coords
    tie = m.groups[(2, tags.URETER_STENT)]
    r = np.hypot(x[tie, 0], x[tie, 1])
    z0, z1 = g.occlusion.contact
    assert len(tie) == info["facet_tags"]["ureter_stent"] > 0
    # the tied facets lie on the stent's outer surface over the contact (chords of it; its edges on the intersection
    # curves, within 1e-5 r_s)
    assert r.max() <= g.stent_outer_radius * (1 + 2e-5) and r.min() > 0.98 * g.stent_outer_radius
    assert x[tie, 2].min() == pytest.approx(z0, abs=1e-9) and x[tie, 2].max() == pytest.approx(z1, abs=1e-9)
    # no urine cell outside the stent lumen in the contact
    fluid = x[m.groups[(3, tags.FLUID)]].mean(axis=1)
    inside = (fluid[:, 2] > z0) & (fluid[:, 2] < z1)
    assert inside.sum() > 0 and np.hypot(fluid[inside, 0], fluid[inside, 1]).max() < g.stent_inner_radius
    # both holes kept, the volumes those of the profile (facetted curved surfaces)
    assert info["hole_channels_found"] == 2
    assert all(abs(v["rel_error"]) < 5e-3 for v in info["subdomain_measure"].values())
    assert info["quality_minSICN"]["min"] > 0.05


# ---- refusals (one line naming the key, before any job) ------------------------------------------------------

@pytest.mark.parametrize("change, key, words", [
    ({"geometry": {"occlusion_position": 0.002}}, "geometry.occlusion_position", "inside the segment"),
    ({"geometry": {"stricture_fraction": 0.5, "stricture_position": 0.005, "stricture_length": 0.004}},
     "geometry.occlusion_length", "one or the other"),
    ({"geometry": {"stent_offset": 0.0005}}, "geometry.occlusion_length", "coaxial stent"),
    ({"study": {"fidelity": "one_way"}}, "study.fidelity", "one_way cannot pose the complete occlusion"),
])
def test_refusals(occluded_cfg, change, key, words):
    from ureterfsi.config.reading import deep_merge
    with pytest.raises(ConfigError) as err:
        load_config(deep_merge(occluded_cfg, change))
    assert err.value.key == key and words in str(err.value) and "\n" not in str(err.value)


def test_models_it_cannot_pose_are_refused_where_their_mesh_is_asked_for(occluded_cfg, tmp_path):
    assert unmakeable(occluded_cfg, "1", "coarse", "quarter").startswith("model 1 has no stent: a complete occlusion")
    assert unmakeable(occluded_cfg, "2", "coarse", "quarter").startswith(
        "model 2: the side-hole pair at z = 0.005 m lies under the occlusion's span")
    assert unmakeable(occluded_cfg, "3", "coarse", "quarter") == ""
    assert unmakeable(occluded_cfg, "4", "coarse", "quarter") == ""
    with pytest.raises(ValueError, match="lies under the occlusion"):
        build_mesh(occluded_cfg, "2", "coarse", "quarter", tmp_path / "m.msh", tmp_path / "m.json")


def test_one_way_rung_refuses_the_occlusion(occluded_cfg, tmp_path):
    with pytest.raises(SystemExit, match="one-way rung cannot pose a complete occlusion"):
        oneway.run(occluded_cfg, RunSpec("3", "coarse", "quarter", str(tmp_path / "m.msh")), str(tmp_path / "o.nc"))
    with pytest.raises(SystemExit, match="one-way rung cannot pose a complete occlusion"):
        oneway.write_wall_motion(occluded_cfg, str(tmp_path / "wall.nc"))
    assert not list(tmp_path.iterdir())   # nothing written


# ---- fully coupled rung: mass balance and tie ----------------------------------------------------------------

class OcclusionBalance(Observer):
    """Per step: Q_in, Q_cut, S (module docstring) of four P1 indicators of the fluid's vertices: upstream and
    downstream of the cut z_o, and the annulus (r >= r_s) on either side; each Q_cut also over the cells inside the
    stent's outer radius (at the cut: its lumen) and over those within a hole diameter of a hole's axis."""

    def __init__(self, pb: MonolithicFSI, geom: UreterGeometry, z_holes: np.ndarray):
        mesh, tdim = pb.mesh, pb.mesh.topology.dim
        P, _ = pb.sub("pressure").collapse()
        X = P.tabulate_dof_coordinates()
        fluid_dofs = fem.locate_dofs_topological(P, tdim, pb.cells([tags.FLUID]))
        r, z = np.hypot(X[:, 0], X[:, 1]), X[:, 2]
        # the stent's outer surface: its nodes on the intersection curves (hole rims, the contact's edges) lie within
        # ~1e-5 r_s of it, the holes' next nodes a hole element inside
        up, annulus = z < geom.occlusion.position, r > geom.stent_outer_radius * (1 - 1e-4)
        masks = {"up": up, "down": ~up, "annulus_up": up & annulus, "annulus_down": ~up & annulus}
        D = fem.FunctionSpace(mesh, ("DG", 0))
        mid = D.tabulate_dof_coordinates()
        stent = fem.Function(D)   # 1 on the cells inside the stent's outer radius (its lumen at the cut)
        stent.x.array[:] = np.hypot(mid[:, 0], mid[:, 1]) < geom.stent_outer_radius
        holes = fem.Function(D)   # 1 on the cells within a hole diameter of a hole's axis (its channel and mouth)
        holes.x.array[:] = (np.abs(mid[:, 2, None] - z_holes[None, :]) < 2 * geom.hole_radius).any(axis=1)
        parts, rates = pb.split(), pb.split(pb.x_dot)
        v, u, w = parts["velocity"], parts["displacement"], rates["displacement"]
        F = ufl.Identity(3) + ufl.grad(u)
        cof = ufl.det(F) * ufl.inv(F).T
        rel, N = v - w, ufl.FacetNormal(mesh)
        md = {"quadrature_degree": 6}
        dx = ufl.Measure("dx", domain=mesh, subdomain_data=pb.scene.cell_tags, metadata=md)(tags.FLUID)
        ds = ufl.Measure("ds", domain=mesh, subdomain_data=pb.scene.facet_tags, metadata=md)
        self.forms, self.records, self.comm = {}, [], mesh.comm
        for name, mask in masks.items():
            q = fem.Function(P)
            q.x.array[fluid_dofs[mask[fluid_dofs]]] = 1.0
            cut = -ufl.dot(cof * ufl.grad(q), rel)
            self.forms[name] = {
                "inlet": fem.form(-q * ufl.dot(rel, cof * N) * ds(tags.INLET)),
                "outlet": fem.form(q * ufl.dot(rel, cof * N) * ds(tags.OUTLET)),
                "cut": fem.form(cut * dx), "cut_stent": fem.form(stent * cut * dx),
                "cut_holes": fem.form(holes * cut * dx),
                "storage": fem.form(q * ufl.tr(ufl.grad(w) * cof.T) * dx)}
            self.forms[name]["_q"] = q   # keep the coefficient alive

    def value(self, form) -> float:
        return self.comm.allreduce(fem.assemble_scalar(form), op=MPI.SUM)

    def observe(self, problem, step):
        if step:
            self.records.append({k: {n: self.value(f) for n, f in fs.items() if n != "_q"}
                                 for k, fs in self.forms.items()})


class Tie(Observer):
    """Per step: the largest difference between the displacement seen from the wall's cell and from the stent's
    cell at the midpoint of every tied facet, and the largest displacement there."""

    def __init__(self, pb: MonolithicFSI):
        mesh, tdim = pb.mesh, pb.mesh.topology.dim
        mesh.topology.create_connectivity(tdim - 1, tdim)
        f2c = mesh.topology.connectivity(tdim - 1, tdim)
        facets = pb.scene.facet_tags.find(tags.URETER_STENT)
        kind = {int(c): int(t) for c, t in zip(pb.scene.cell_tags.indices, pb.scene.cell_tags.values)}
        wall, stent = [], []
        for f in facets:
            cells = f2c.links(f)
            by_tag = {kind[int(c)]: int(c) for c in cells}
            wall.append(by_tag[tags.URETER])
            stent.append(by_tag[tags.STENT])
        self.points = compute_midpoints(mesh, tdim - 1, facets)
        self.wall, self.stent, self.pb, self.records = np.array(wall), np.array(stent), pb, []

    def observe(self, problem, step):
        u = problem.field("displacement")
        a, b = u.eval(self.points, self.wall), u.eval(self.points, self.stent)
        self.records.append((float(np.abs(a - b).max(initial=0.0)), float(np.abs(a).max(initial=0.0))))


@pytest.fixture(scope="module")
def coupled(occluded_cfg, occluded_mesh):
    mesh, cell_tags, facet_tags = load_mesh(occluded_mesh[0], MPI.COMM_WORLD)
    pb = MonolithicFSI(ureter_scene(occluded_cfg, mesh, cell_tags, facet_tags), solver_options(occluded_cfg, True))
    g = UreterGeometry.from_config(occluded_cfg)
    z_holes = hole_pair_positions(g, StentModel.from_config(occluded_cfg, "3"))
    balance, tie = OcclusionBalance(pb, g, z_holes), Tie(pb)
    TimeIntegrator(pb, TimeSettings(end=0.04, dt=occluded_cfg["time"]["dt"]), [balance, tie]).run()
    return balance.records, tie.records


def test_lumen_carries_everything_past_the_occlusion(coupled):
    """Q_in - S_up = Q_cut = Q_out + S_down: what enters and is not stored upstream passes the occlusion, all of it
    through the stent lumen (the cut's flux over the stent's cells alone is the whole of it)."""
    records, _ = coupled
    for rec in records:
        up, down = rec["up"], rec["down"]
        scale = max(abs(up["inlet"]), abs(down["outlet"]))
        lumen = up["cut"]
        print(f"\nQ_in {up['inlet']:.4e}, S_up {up['storage']:.4e}, lumen at the occlusion {lumen:.4e}, "
              f"Q_out {down['outlet']:.4e}, S_down {down['storage']:.4e} m^3/s; "
              f"balance up {(up['inlet'] - lumen - up['storage']) / scale:.1e}, "
              f"down {(-lumen - down['cut']) / scale:.1e}, {(lumen - down['outlet'] - down['storage']) / scale:.1e}")
        assert abs(lumen) > 1e-6 * scale            # urine does pass the occlusion, 1e3 x the balance's tolerance
        assert up["inlet"] - lumen - up["storage"] == pytest.approx(0.0, abs=1e-9 * scale)
        assert lumen - down["outlet"] - down["storage"] == pytest.approx(0.0, abs=1e-9 * scale)
        assert up["cut_stent"] == pytest.approx(lumen, rel=1e-12, abs=1e-12 * scale)


def test_holes_take_in_upstream_what_passes_and_give_it_out_downstream(coupled):
    """Per side: the holes' flux (annulus -> lumen upstream, lumen -> annulus downstream) balances the annulus'
    end face and storage, and the annulus has no path past the occlusion (its cut lies at the holes)."""
    records, _ = coupled
    for rec in records:
        a_up, a_down = rec["annulus_up"], rec["annulus_down"]
        scale = max(abs(rec["up"]["inlet"]), abs(rec["down"]["outlet"]))
        intake, outgo = a_up["cut"], -a_down["cut"]
        print(f"\nupstream holes take in {intake:.4e} (annulus inlet {a_up['inlet']:.4e}, storage "
              f"{a_up['storage']:.4e}); downstream holes give out {outgo:.4e} (annulus outlet {a_down['outlet']:.4e}, "
              f"storage {a_down['storage']:.4e}) m^3/s")
        assert intake == pytest.approx(a_up["inlet"] - a_up["storage"], abs=1e-9 * scale)
        assert outgo == pytest.approx(a_down["outlet"] + a_down["storage"], abs=1e-9 * scale)
        assert a_up["cut_holes"] == pytest.approx(intake, rel=1e-12, abs=1e-12 * scale)
        assert a_down["cut_holes"] == pytest.approx(-outgo, rel=1e-12, abs=1e-12 * scale)


def test_wall_and_stent_displacements_are_equal_on_the_tie(coupled):
    _, records = coupled
    jump, largest = max(r[0] for r in records), max(r[1] for r in records)
    print(f"\ntie: largest displacement {largest:.3e} m, largest jump {jump:.1e} m")
    assert largest > 1e-7 and jump <= 1e-12 * largest
