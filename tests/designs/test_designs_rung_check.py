"""Design studies, "trust at every point" (ureterfsi.designs.rung_check): the corners of a study's design space,
the region they check, the corners' configurations on the 10 mm segment, the dataset's rung errors from synthetic
run files, and the corner jobs of a dry run. The end to end run is tests/designs/test_designs.py's 2 x 2 grid."""
from __future__ import annotations

import copy
import json
from pathlib import Path

import numpy as np
import pytest
import xarray as xr
import yaml

from ureterfsi.designs import rung_check as rc
from ureterfsi.config import ConfigError, load_config
from ureterfsi.config.reading import deep_merge
from ureterfsi.designs.expand import corner_run_paths, studies
from ureterfsi.designs.space import point_id
from ureterfsi.designs.results import QUANTITIES, rung_check_dataset, study_dataset
from ureterfsi.data import cf as metadata
from ureterfsi.data.cf import rung_check_metadata
from ureterfsi.data.provenance import FORMAT_VERSION, FORMAT_VERSION_ATTR
from helpers.design_runs import fake_run, stamp, stamp_corners

REPO = Path(__file__).resolve().parents[2]
BASE = yaml.safe_load((REPO / "config" / "config.yaml").read_text())
MINI = yaml.safe_load((REPO / "config" / "segment-10mm.yaml").read_text())


def grid(model="3", check=None, **params):
    spec = {"model": model, "level": "coarse", "grid": {"mode": "full_factorial", "parameters": params}}
    return spec | ({"rung_check": check} if check is not None else {})


def config_with(base=BASE, **specs) -> dict:
    return load_config(base, {"design_studies": specs})


# ------------------------------------------------------------------------------------------ corners, region (pure)

def test_corners_every_combination_or_each_axis():
    lo, hi = {"a": 0.0, "b": 1.0, "c": 5.0}, {"a": 1.0, "b": 3.0, "c": 5.0}     # c not varied
    base = {"a": 0.2, "b": 9.0, "c": 5.0}
    assert rc.corner_values("all", lo, hi, base) == [{"a": a, "b": b, "c": 5.0} for a in (0.0, 1.0) for b in (1.0, 3.0)]
    # axes: each varied parameter at its ends, the others at the base clipped to their range (b: 9 -> 3)
    assert rc.centre(lo, hi, base) == {"a": 0.2, "b": 3.0, "c": 5.0}
    assert rc.corner_values("axes", lo, hi, base) == [{"a": 0.0, "b": 3.0, "c": 5.0}, {"a": 1.0, "b": 3.0, "c": 5.0},
                                                      {"a": 0.2, "b": 1.0, "c": 5.0}, {"a": 0.2, "b": 3.0, "c": 5.0}]
    # auto: every corner up to 3 varied parameters (8), the axes above (2 D instead of 2^D)
    for d, mode, n in ((3, "all", 8), (4, "axes", 8), (5, "axes", 10)):
        lo, hi = {f"x{i}": 0.0 for i in range(d)}, {f"x{i}": 1.0 for i in range(d)}
        assert rc.corner_mode("auto", lo, hi) == mode
        assert len(rc.corner_values(mode, lo, hi, {k: 0.5 for k in lo})) == n
    assert rc.corner_mode("auto", {"a": 0, "b": 0, "c": 0, "d": 1}, {"a": 1, "b": 1, "c": 1, "d": 1}) == "all"


def test_checked_region():
    lo, hi, base = {"a": 0.0, "b": 0.0}, {"a": 2.0, "b": 4.0}, {"a": 1.0, "b": 1.0}
    # all: the box
    assert rc.inside({"a": 2.0, "b": 0.0}, "all", lo, hi, base) and rc.inside({"a": 1.3, "b": 3.9}, "all", lo, hi, base)
    assert not rc.inside({"a": 2.1, "b": 1.0}, "all", lo, hi, base)
    # axes: the corners' hull around the centre (1, 1): |a - 1| / 1 + (b - 1) / 3 (b above) or (1 - b) / 1 (below)
    assert rc.inside({"a": 1.0, "b": 4.0}, "axes", lo, hi, base) and rc.inside({"a": 1.5, "b": 2.5}, "axes", lo, hi, base)
    assert not rc.inside({"a": 1.5, "b": 2.6}, "axes", lo, hi, base)
    assert not rc.inside({"a": 2.0, "b": 0.0}, "axes", lo, hi, base)            # a box corner: outside the hull
    # a parameter at one end of its range at the centre: no corner on the other side
    assert rc.region_distance({"a": 1.0, "b": 4.5}, "axes", lo, hi, {"a": 1.0, "b": 4.0}) == np.inf


def test_relative_errors():
    e = rc.relative_errors({"p": 1.1, "q": 0.0, "r": 2.0, "s": np.nan}, {"p": 1.0, "q": 0.0, "r": 0.0, "s": 1.0},
                           ["p", "q", "r", "s"])
    assert e[0] == pytest.approx(0.1) and e[1] == 0.0 and np.isnan(e[2]) and np.isnan(e[3])
    # a scale of the quantity (a peak outlet flow near 0 against the flow's largest |Q|)
    e = rc.relative_errors({"p": 0.0, "r": 2.0}, {"p": 1e-12, "r": 0.0}, ["p", "r"], {"p": 1e-9, "r": 4.0})
    assert e.tolist() == pytest.approx([1e-3, 0.5])


def test_outlet_flow_errors_are_relative_to_the_flow():
    """The peak and mean outlet flow's errors over the run's largest |Q_out|, the backflow's over integral |Q_out| dt."""
    from ureterfsi.designs.results import error_scales

    t = np.linspace(0.0, 0.04, 5)
    run = xr.Dataset({"outlet_flux": ("time", np.array([0.0, -2.0, -4.0, 1.0, 2.0]))}, coords={"time": t})
    s = error_scales(run)
    assert s["peak_outlet_flux"] == s["mean_outlet_flux"] == 4.0
    assert s["backflow_volume"] == pytest.approx(0.01 * (1 + 3 + 2.5 + 1.5))


# ------------------------------------------------------------------------------------------ a study's corners

def test_corners_of_a_50_mm_study_on_the_segment():
    """A one-way grid on the 50 mm model: its corners on the 10 mm segment (mini overlay's geometry, load start and
    time window; the model's spacing kept, its hole count by the Table 1 rule), each with its mesh and wall, the
    fully coupled reference on the partitioned scheme; no point reused (another length)."""
    st = studies(config_with(s=grid(hole_diameter=[5e-4, 6e-4, 7e-4], hole_pair_spacing=[0.005, 0.025])))["s"]
    ch = st.check
    assert ch.mode == "all" and ch.tolerance == 0.05 and not ch.on_segment and ch.reuses == {}
    assert [c.values for c in ch.corners] == [{"hole_diameter": d, "hole_pair_spacing": s}
                                              for d in (5e-4, 7e-4) for s in (0.005, 0.025)]
    assert [c.id for c in ch.corners] == [point_id(c.values) for c in ch.corners]
    for c in ch.corners:
        g = c.config["geometry"]
        assert g["length"] == MINI["geometry"]["length"] and c.config["time"] == BASE["time"] | MINI["time"]
        assert c.config["peristalsis"]["start_position"] == MINI["peristalsis"]["start_position"]
        assert g["hole_diameter"] == c.values["hole_diameter"] and c.symmetry == "quarter"
        assert c.config["models"]["3"]["holes"] == {0.005: 6, 0.025: 2}[c.values["hole_pair_spacing"]]
    assert len({c.mesh_id for c in ch.corners}) == 4 and len({c.wall_id for c in ch.corners}) == 1
    assert {c.mesh_id for c in ch.corners}.isdisjoint({p.mesh_id for p in st.points})
    paths = corner_run_paths(st)
    assert paths[ch.corners[0].id] == (f"results/designs/s/rung_check/{ch.corners[0].id}/one_way.nc",
                                       f"results/designs/s/rung_check/{ch.corners[0].id}/fully_coupled.nc")
    from ureterfsi.designs.expand import corner_solve_request

    c, ref = corner_solve_request(st, ch.corners[0].id, "fully_coupled")
    assert ref["solver"]["fully_coupled_scheme"] == "partitioned" and c.config["solver"]["fully_coupled_scheme"] == \
        BASE["solver"]["fully_coupled_scheme"]
    assert all(ch.inside(p.values) for p in st.points)


def test_a_study_on_the_segment_reuses_its_corner_points():
    """On the segment itself (the mini overlay) a grid's corners are its points: their one-way runs serve the check,
    only the fully coupled solves are new."""
    mini = deep_merge(BASE, MINI)
    st = studies(config_with(mini, s=grid(model="2", hole_diameter=[5e-4, 6e-4, 7e-4],
                                         wall_stiffness_scale=[0.5, 1.5])))["s"]
    ch = st.check
    assert ch.on_segment and len(ch.corners) == 4 and ch.reuses == {c.id: c.id for c in ch.corners}
    for c in ch.corners:
        p = st.point(c.id)
        assert (c.mesh_id, c.wall_id, c.symmetry) == (p.mesh_id, p.wall_id, p.symmetry)
        assert corner_run_paths(st)[c.id][0] == f"results/designs/s/{c.id}/run.nc"


def test_axes_corners_of_a_four_parameter_sample():
    """D = 4 under auto: the 8 axis corners around the base (clipped to the bounds), not 16; the sample's points
    outside their hull (a cross-polytope) are outside the checked region."""
    bounds = {"peak_traction": [3e4, 7e4], "wall_stiffness_scale": [0.5, 1.5], "hole_diameter": [5e-4, 9e-4],
              "pulse_speed": [0.01, 0.03]}
    spec = {"model": "3", "level": "coarse", "sample": {"method": "latin_hypercube", "size": 6, "seed": 1,
                                                        "bounds": bounds}}
    st = studies(config_with(s=spec))["s"]
    ch = st.check
    assert ch.mode == "axes" and len(ch.corners) == 8
    base = {"peak_traction": BASE["peristalsis"]["peak_traction"], "wall_stiffness_scale": 1.0,
            "hole_diameter": BASE["geometry"]["hole_diameter"], "pulse_speed": BASE["peristalsis"]["speed"]}
    assert ch.centre == {p: min(max(base[p], lo), hi) for p, (lo, hi) in bounds.items()}
    for p, ends in bounds.items():          # each end once, the others at the centre (the base hole, 5e-4 m, is one)
        along = [c.values[p] for c in ch.corners if all(c.values[q] == ch.centre[q] for q in bounds if q != p)]
        assert set(ends) <= set(along), p
    assert sum(not ch.inside(p.values) for p in st.points) > 0          # a sample reaches outside the cross-polytope
    # configured all: the 16 corners
    spec["rung_check"] = {"corners": "all"}
    assert len(studies(config_with(s=spec))["s"].check.corners) == 16


def test_rung_check_options_and_refusals():
    assert studies(config_with(s=grid(hole_diameter=[5e-4], check={"corners": "none"})))["s"].check is None
    fc = grid(hole_diameter=[5e-4, 6e-4]) | {"rung": "fully_coupled"}
    assert studies(config_with(s=fc))["s"].check is None                  # nothing to check by default
    with pytest.raises(ConfigError, match=r"^config error: design_studies.s.rung_check.corners: the study's rung is "
                                          r"fully_coupled already"):
        config_with(s=fc | {"rung_check": {"corners": "all"}})
    with pytest.raises(ConfigError, match=r"^config error: design_studies.s.rung_check.tolerance"):
        config_with(s=grid(hole_diameter=[5e-4], check={"tolerance": 0}))
    with pytest.raises(ConfigError, match=r"^config error: design_studies.s.rung_check.segment: no such overlay"):
        config_with(s=grid(hole_diameter=[5e-4], check={"segment": "nowhere.yaml"}))
    # a stricture of the 50 mm model at 25 mm does not fit the 10 mm segment: refused in one line, before any job
    with pytest.raises(ConfigError) as err:
        config_with(s=grid(stricture_fraction=[0.0, 0.5], stricture_length=[0.004], stricture_position=[0.025]))
    msg = str(err.value)
    assert "\n" not in msg and msg.startswith("config error: design_studies.s.rung_check: corner ") and \
        "cannot be posed on the segment config/segment-10mm.yaml: geometry.stricture_position" in msg, msg


# ------------------------------------------------------------------------------------------ the dataset

def _synthetic(tmp_path: Path, cfg: dict, rung_error):
    """Run files of study s: every point and each corner's one-way run with a peak flow 1e-9 (1 + hole diameter
    / 1 m), the fully coupled one off by rung_error(corner values) in the peak flow; the dataset."""
    st = studies(cfg)["s"]
    paths = {}
    for p in st.points:
        paths[p.id] = tmp_path / f"{p.id}.nc"
        fake_run(paths[p.id], 1e-9 * (1 + p.values["hole_diameter"]), 1e-5)
    corners = {}
    for c in st.check.corners:
        peak = 1e-9 * (1 + c.values["hole_diameter"])
        corners[c.id] = (tmp_path / f"{c.id}_rung.nc", tmp_path / f"{c.id}_ref.nc")
        fake_run(corners[c.id][0], peak, 1e-5, 2.0)
        fake_run(corners[c.id][1], peak / (1 + rung_error(c.values)), 1e-5, 7.0)
    check = rung_check_dataset(cfg, "s", stamp_corners(st, corners))
    assert check.attrs["rung_check"] in study_dataset(cfg, "s", stamp(st, paths), check).attrs["rung_check"]   # + the points
    return st, study_dataset(cfg, "s", stamp(st, paths), check)


def test_dataset_records_the_rung_error_per_corner(tmp_path):
    cfg = config_with(s=grid(hole_diameter=[5e-4, 6e-4, 7e-4], peak_traction=[4e4, 5e4]))
    st, ds = _synthetic(tmp_path, cfg, lambda v: 0.01 + 0.02 * (v["peak_traction"] > 4.5e4))
    ch = st.check
    assert ds["rung_error"].dims == ("corner", "quantity") and list(ds["quantity"].values) == list(QUANTITIES)
    assert list(ds["corner"].values) == [c.id for c in ch.corners]
    assert list(ds["corner_peak_traction"].values) == [4e4, 5e4, 4e4, 5e4]
    e = ds["rung_error"].sel(quantity="peak_outlet_flux").values
    assert np.allclose(e, [0.01, 0.03, 0.01, 0.03], rtol=1e-9)
    assert np.allclose(ds["rung_error"].sel(quantity="peak_wall_displacement").values, 0.0)
    assert np.isnan(ds["rung_error"].sel(quantity="peak_stent_von_mises").values).all()      # not recorded
    assert float(ds["max_rung_error"].sel(quantity="peak_outlet_flux")) == pytest.approx(0.03)
    assert float(ds["rung_tolerance"]) == 0.05 and ds.attrs["rung_check_tolerance"] == 0.05
    assert ds.attrs["rung_check_max_error"] == pytest.approx(0.03)
    assert (ds["corner_within_tolerance"].values == 1).all() and (ds["corner_reference_wall_time"].values == 7.0).all()
    # per point, on the grid's dimensions: inside the checked box, every corner within the tolerance
    assert ds["rung_trusted"].dims == ("hole_diameter", "peak_traction") and (ds["rung_trusted"].values == 1).all()
    assert (ds["in_rung_check_region"].values == 1).all()
    text = ds.attrs["rung_check"]
    assert text.startswith("one_way checked against fully_coupled (partitioned) at 4 corners (all) of the design "
                           "space on the segment config/segment-10mm.yaml: largest relative error 0.03 "
                           "(tolerance 0.05); every corner within it; every design point inside the checked region"), text
    meta = rung_check_metadata(st.parameters)
    for k in ("rung_error", "max_rung_error", "rung_tolerance", "corner", "corner_hole_diameter", "rung_trusted",
              "in_rung_check_region", "corner_within_tolerance"):
        assert (ds[k].attrs["units"], ds[k].attrs["long_name"]) == meta[k], k
    assert ds["corner_hole_diameter"].attrs["units"] == "m" and ds["rung_error"].attrs["units"] == "1"
    from ureterfsi.data.cf import write_netcdf

    write_netcdf(ds, tmp_path / "s.nc")                      # CF-safe: what rule design_dataset writes
    back = xr.load_dataset(tmp_path / "s.nc", decode_times=False)
    assert np.allclose(back["rung_error"].values, ds["rung_error"].values, equal_nan=True)
    assert json.loads(back.attrs["rung_check_outside_points"]) == []


def test_dataset_names_corners_beyond_the_tolerance_and_points_outside(tmp_path):
    """A corner over the tolerance distrusts every point; an axes check leaves a grid's box corners outside its
    region; the attribute names both."""
    cfg = config_with(s=grid(hole_diameter=[5e-4, 6e-4, 7e-4], peak_traction=[4e4, 5e4, 6e4],
                             check={"corners": "axes", "tolerance": 0.02}))
    st, ds = _synthetic(tmp_path, cfg, lambda v: 0.08 if v["hole_diameter"] == 7e-4 else 0.001)
    ch = st.check
    assert ch.mode == "axes" and len(ch.corners) == 4
    bad = [c.id for c in ch.corners if c.values["hole_diameter"] == 7e-4]
    assert list(ds["corner_within_tolerance"].values) == [int(c.id not in bad) for c in ch.corners]
    inside = ds["in_rung_check_region"].transpose("hole_diameter", "peak_traction").values
    centre = (ch.centre["hole_diameter"], ch.centre["peak_traction"])
    assert centre == (5e-4, 5e4)                             # the base values (5e-4 m, 5e4 Pa) in range
    assert inside.tolist() == [[1, 1, 1], [0, 1, 0], [0, 1, 0]]  # (d - 5e-4) / 2e-4 + |p - 5e4| / 1e4 <= 1
    assert (ds["rung_trusted"].values == 0).all()
    text = ds.attrs["rung_check"]
    assert f"corners beyond the tolerance: {bad[0]}" in text and "4 of 9 design points outside the checked region" in text
    assert json.loads(ds.attrs["rung_check_corners_beyond_tolerance"]) == bad


def test_an_unchecked_study_says_so(tmp_path):
    cfg = config_with(s=grid(hole_diameter=[5e-4, 6e-4], check={"corners": "none"}))
    st = studies(cfg)["s"]
    paths = {}
    for p in st.points:
        paths[p.id] = tmp_path / f"{p.id}.nc"
        fake_run(paths[p.id], 1e-9, 1e-5)
    ds = study_dataset(cfg, "s", stamp(st, paths))
    assert "rung_error" not in ds and (ds["rung_trusted"].values == 0).all()
    assert ds.attrs["rung_check"].startswith("not checked (design_studies.s.rung_check.corners: none)")


# ------------------------------------------------------------------------------------------ the job plan

def test_dry_run_lists_the_corner_jobs(tmp_path):
    """design_<study> of a 3 x 2 grid on the 50 mm model: its 6 points and the 4 corners' one-way and fully coupled
    solves on the segment (their own meshes and wall); design_<study>_rung_check the corners alone."""
    from helpers.design_runs import dry_run

    cfg = copy.deepcopy(BASE)
    cfg["design_studies"] = {"s": grid(hole_diameter=[5e-4, 6e-4, 7e-4], hole_pair_spacing=[0.005, 0.025])}
    counts = dry_run(tmp_path, cfg, "design_s")
    assert counts == {"design_solve": 6, "design_mesh": 6 + 4, "design_wall_motion": 1 + 1, "design_corner_solve": 8,
                      "design_rung_check": 1, "design_dataset": 1, "design_figures": 1, "design_map": 1,
                      "design_s": 1}, counts
    assert dry_run(tmp_path, cfg, "design_s_rung_check") == {"design_mesh": 4, "design_wall_motion": 1,
                                                          "design_corner_solve": 8, "design_rung_check": 1,
                                                          "design_s_rung_check": 1}
    # on the segment: the corner points' one-way runs serve the check, only the 4 fully coupled solves are added
    mini = deep_merge(copy.deepcopy(BASE), MINI)
    mini["design_studies"] = {"s": grid(model="2", hole_diameter=[5e-4, 6e-4, 7e-4], hole_pair_spacing=[0.005, 0.01])}
    counts = dry_run(tmp_path, mini, "design_s")
    assert counts == {"design_solve": 6, "design_mesh": 6, "design_wall_motion": 1, "design_corner_solve": 4,
                      "design_rung_check": 1, "design_dataset": 1, "design_figures": 1, "design_map": 1,
                      "design_s": 1}, counts


def test_shipped_studies_are_checked():
    """Every shipped one-way study gets the check; on the command line's overlays (the 10 mm segment for the studies
    shipped for it, the study's own segment for hole_diameter_spacing) the corners that are grid points reuse them;
    the fully coupled studies need none."""
    reuse = {"hole_diameter_spacing": 4, "stricture": 4, "thin_gap": 2, "arrangement_offset": 4,
             "obstruction_sobol": 0, "stricture_holes": 8}
    on_50_mm = ("hole_diameter_spacing", "occlusion_holes", "stricture_holes", "voiding_reflux", "encrustation")
    for f in sorted((REPO / "config" / "designs").glob("*.yaml")):
        name, overlay = f.stem, yaml.safe_load(f.read_text())
        base = BASE if name in on_50_mm else deep_merge(BASE, MINI)
        st = studies(load_config(deep_merge(base, overlay)))[name]
        if st.rung == rc.REFERENCE_RUNG:
            assert st.check is None, name
            continue
        assert st.check is not None and st.check.mode == "all", name
        assert len(st.check.reuses) == reuse[name], (name, st.check.reuses)


def test_only_a_moved_corner_reruns(tmp_path):
    """Corners are content-addressed like the points: an interior point's change re-runs that point alone; moving
    the design space's maximum hole diameter re-runs the two corners there (their mesh, both their solves) besides
    the moved points."""
    from helpers.design_runs import dry_run, pretend_done
    from helpers.snakemake_runs import ok, snakemake

    cfg = copy.deepcopy(BASE)
    cfg["design_studies"] = {"s": grid(hole_diameter=[5e-4, 6e-4, 7e-4], wall_stiffness_scale=[0.5, 1.5])}
    path = tmp_path / "cfg.yaml"
    path.write_text(yaml.safe_dump(cfg, sort_keys=False))
    pretend_done(tmp_path, cfg, "s")
    ok(snakemake(tmp_path, path, "--touch", "--cores", "1", "design_s", profile=None))
    assert dry_run(tmp_path, cfg, "design_s") == {}
    cfg["design_studies"]["s"]["grid"]["parameters"]["hole_diameter"][1] = 6.5e-4
    assert dry_run(tmp_path, cfg, "design_s") == {"design_mesh": 1, "design_solve": 2, "design_dataset": 1,
                                               "design_figures": 1, "design_map": 1, "design_s": 1}
    cfg["design_studies"]["s"]["grid"]["parameters"]["hole_diameter"][1:] = [6e-4, 8e-4]
    assert dry_run(tmp_path, cfg, "design_s") == {"design_mesh": 1 + 1, "design_solve": 2, "design_corner_solve": 2 * 2,
                                               "design_rung_check": 1, "design_dataset": 1, "design_figures": 1,
                                               "design_map": 1, "design_s": 1}


def test_a_corner_whose_solve_failed_is_reported_not_checked(tmp_path):
    """A fully coupled corner solve that fails (the thin-gap corner f = 0.7 inverts the harmonic mesh motion at 40
    ms) is recorded by its job as a run file holding the failure: the check names it, no error is claimed there, and
    no point is trusted."""
    from ureterfsi.study.run import write_failed_run

    cfg = config_with(s=grid(hole_diameter=[5e-4, 6e-4], peak_traction=[4e4, 5e4]))
    st = studies(cfg)["s"]
    paths, corners = {}, {}
    for p in st.points:
        paths[p.id] = tmp_path / f"{p.id}.nc"
        fake_run(paths[p.id], 1e-9, 1e-5)
    for i, c in enumerate(st.check.corners):
        corners[c.id] = (tmp_path / f"{c.id}_rung.nc", tmp_path / f"{c.id}_ref.nc")
        fake_run(corners[c.id][0], 1e-9, 1e-5)
        if i == 0:
            write_failed_run(c.config, corners[c.id][1], "fully_coupled", "(fully_coupled) failed: ALE mesh inverted")
        else:
            fake_run(corners[c.id][1], 1e-9, 1e-5)
    check = rung_check_dataset(cfg, "s", stamp_corners(st, corners))
    first = st.check.corners[0].id
    assert np.isnan(check["rung_error"].sel(corner=first).values).all()
    assert check["corner_within_tolerance"].values.tolist() == [0, 1, 1, 1]
    assert json.loads(check.attrs["rung_check_failed_corners"]) == {first: "(fully_coupled) failed: ALE mesh inverted"}
    ds = study_dataset(cfg, "s", stamp(st, paths), check)
    text = ds.attrs["rung_check"]
    assert f"every corner solved within it; not checked (a solve failed) at {first}: (fully_coupled) failed" in text
    assert (ds["rung_trusted"].values == 0).all() and (ds["in_rung_check_region"].values == 1).all()


def test_a_corrupt_corner_run_file_is_named_in_one_line(tmp_path):
    """The rung check reads its corners' run files through checked_io: a truncated one is a BadFile naming it."""
    from ureterfsi.data.checked import BadFile

    cfg = config_with(s=grid(hole_diameter=[5e-4, 6e-4], peak_traction=[4e4, 5e4]))
    st = studies(cfg)["s"]
    corners = {}
    for c in st.check.corners:
        corners[c.id] = (tmp_path / f"{c.id}_rung.nc", tmp_path / f"{c.id}_ref.nc")
        for path in corners[c.id]:
            fake_run(path, 1e-9, 1e-5)
    stamp_corners(st, corners)
    bad = corners[st.check.corners[1].id][1]
    bad.write_bytes(bad.read_bytes()[:300])
    with pytest.raises(BadFile) as err:
        rung_check_dataset(cfg, "s", corners)
    assert str(err.value).startswith(f"{bad}: ") and "\n" not in str(err.value)
