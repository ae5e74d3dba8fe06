"""Whole-passage design studies (ureterfsi.designs.passage; config/designs/{occlusion_holes, stricture_holes,
voiding_reflux, encrustation}.yaml): the shipped studies expand and validate without solving; a study's base
overlay and reference runs; the escalation of the points nearest a failing corner (the region, the dataset's rung,
the jobs of a dry run); the passage quantities of a design dataset from synthetic run files, CF-checked; and the
2 x 2 occlusion study on the 10 mm segment from configuration to dataset and figures (slow)."""
from __future__ import annotations

import copy
import json
import os
from pathlib import Path

import numpy as np
import pytest
import xarray as xr
import yaml

from ureterfsi.config import ConfigError, load_config
from ureterfsi.config.reading import deep_merge
from ureterfsi.data import cf as metadata
from ureterfsi.data.provenance import FORMAT_VERSION, FORMAT_VERSION_ATTR
from ureterfsi.designs import rung_check as rc
from ureterfsi.designs.expand import studies
from ureterfsi.designs.jobs import solve_config_hash
from ureterfsi.designs.passage import REFERENCE_SCALARS, escalated_points
from ureterfsi.designs.results import study_dataset

REPO = Path(__file__).resolve().parents[2]
BASE = yaml.safe_load((REPO / "config" / "config.yaml").read_text())
MINI = yaml.safe_load((REPO / "config" / "segment-10mm.yaml").read_text())
WHOLE_PASSAGE = ("occlusion_holes", "stricture_holes", "voiding_reflux", "encrustation")


def shipped(name: str) -> dict:
    return load_config(deep_merge(BASE, yaml.safe_load((REPO / "config" / "designs" / f"{name}.yaml").read_text())))


# ------------------------------------------------------------------------------------------ the shipped studies

def test_shipped_whole_passage_studies_expand_on_the_50_mm_segment():
    """Each study: its points on the 50 mm segment over the whole passage (3 s), the coarse quarter mesh, its ends
    and obstruction from its base overlay; the one-way stricture study checked on its own segment, escalating."""
    got = {}
    for name in WHOLE_PASSAGE:
        cfg = shipped(name)
        st = studies(cfg)[name]
        got[name] = (len(st.points), [r.name for r in st.references], st.rung, st.check is not None)
        for p in st.points + st.references:
            c = p.config
            assert c["geometry"]["length"] == 0.05 and c["time"]["end"] == 3.0 and st.level == "coarse", name
            assert c["ends"]["kidney"]["condition"] == "pelvis", name
            assert p.symmetry == ("axisymmetric" if p.model == "1" else "quarter"), (name, p.name)
        assert cfg["ends"]["kidney"]["condition"] == "open"        # the base overlay is the study's alone
    assert got == {"occlusion_holes": (18, ["unstented", "stented"], "fully_coupled", False),
                   "stricture_holes": (18, ["unstented", "stented"], "one_way", True),
                   "voiding_reflux": (9, ["unstented"], "fully_coupled", False),
                   "encrustation": (18, [], "fully_coupled", False)}, got
    occ = studies(shipped("occlusion_holes"))["occlusion_holes"]
    assert {p.config["geometry"]["occlusion_length"] for p in occ.points} == {0.001}
    assert {r.config["geometry"]["occlusion_length"] for r in occ.references} == {0.0}
    assert {p.config["ends"]["bladder"]["condition"] for p in occ.points} == {"pressure"}
    assert len({p.mesh_id for p in occ.points}) == 18 and all(p.wall_id is None for p in occ.points)
    st = studies(shipped("stricture_holes"))["stricture_holes"]
    ch = st.check
    assert ch.on_segment and ch.on_failure == "escalate" and len(ch.corners) == 8 and len(ch.reuses) == 8
    # the corners' fully coupled solves carry the ends on the partitioned sweeps
    assert {rc.reference_config(c.config)["solver"]["fully_coupled_scheme"] for c in ch.corners} == {"partitioned"}
    assert [r.rung for r in st.references] == ["fully_coupled", "one_way"]
    void = studies(shipped("voiding_reflux"))["voiding_reflux"]
    assert {p.config["ends"]["bladder"]["detrusor_pressure"] for p in void.points} == {4903.0}
    assert sorted({round(p.values["stent_outer_diameter"] / rc_french(), 6) for p in void.points}) == [4.8, 6.0, 8.0]
    enc = studies(shipped("encrustation"))["encrustation"]
    assert sorted({p.config["geometry"]["occlusion_length"] for p in enc.points}) == [0.0, 0.001]
    # the points whose flow and WSS around the obstruction are drawn from their field files
    assert [len(studies(shipped(n))[n].field_points) for n in WHOLE_PASSAGE] == [2, 1, 0, 2]
    assert occ.point(occ.field_points[1]).values == {"occlusion_position": 0.0425, "hole_pair_spacing": 0.010,
                                                      "hole_pair_rotation": 90}


def rc_french() -> float:
    from ureterfsi.designs.space import FRENCH

    return FRENCH


def test_encrustation_shares_four_solves_with_occlusion_holes():
    """docs/design-passage.md: encrustation's 0.5 mm holes with the occlusion (pairs every 5, 10, 25 mm) and without
    it (every 10 mm) are occlusion_holes' aligned points at 27.5 mm and its stented reference, to the configuration
    hash the dataset checks a run file against, and no other of its points is."""
    both = load_config(deep_merge(shipped("occlusion_holes"),
                                  yaml.safe_load((REPO / "config" / "designs" / "encrustation.yaml").read_text())))
    occ, enc = studies(both)["occlusion_holes"], studies(both)["encrustation"]
    occ_hashes = {solve_config_hash(occ, p.id, occ.rung): p for p in occ.points + occ.references}
    shared = {}
    for p in enc.points:
        twin = occ_hashes.get(solve_config_hash(enc, p.id, enc.rung))
        if twin is not None:
            shared[(p.values["hole_pair_spacing"], p.values["occlusion_length"])] = (
                twin.name if twin in occ.references else
                (twin.values["occlusion_position"], twin.values["hole_pair_spacing"], twin.values["hole_pair_rotation"]))
            assert p.values["hole_diameter"] == 0.0005, p.values
    assert shared == {(0.005, 0.001): (0.0275, 0.005, 0), (0.010, 0.001): (0.0275, 0.010, 0),
                      (0.025, 0.001): (0.0275, 0.025, 0), (0.010, 0.0): "stented"}, shared


def test_occlusion_points_that_cannot_be_posed_are_refused_in_one_line():
    """An occlusion over a hole pair, or a reference without a stent under the occlusion: one line naming the key."""
    overlay = yaml.safe_load((REPO / "config" / "designs" / "occlusion_holes.yaml").read_text())
    bad = copy.deepcopy(overlay)
    bad["design_studies"]["occlusion_holes"]["grid"]["parameters"]["occlusion_position"] = [0.025]
    with pytest.raises(ConfigError) as err:
        load_config(deep_merge(BASE, bad))
    msg = str(err.value)
    assert "\n" not in msg and msg.startswith(
        "config error: design_studies.occlusion_holes.grid.parameters.occlusion_position: point ") and \
        "lies under the occlusion's span" in msg, msg
    bad = copy.deepcopy(overlay)
    bad["design_studies"]["occlusion_holes"]["references"][0]["overlay"] = {}
    with pytest.raises(ConfigError) as err:
        load_config(deep_merge(BASE, bad))
    msg = str(err.value)
    assert "\n" not in msg and msg.startswith("config error: design_studies.occlusion_holes.references.0: reference "
                                              "unstented (model 1) cannot be posed: model 1 has no stent"), msg
    bad = copy.deepcopy(overlay)
    bad["design_studies"]["occlusion_holes"]["rung"] = "one_way"
    with pytest.raises(ConfigError) as err:
        load_config(deep_merge(BASE, bad))
    assert "one_way cannot pose the complete occlusion" in str(err.value)


@pytest.mark.parametrize("entry,key,message", [
    ({"occlusion_position": 0.0275, "hole_diameter": 0.0005}, "field_figures.0.hole_diameter",
     "must be a parameter of the study ['occlusion_position', 'hole_pair_spacing', 'hole_pair_rotation']"),
    ({"occlusion_position": 0.0275}, "field_figures.0", "must select exactly one design point, selects 6"),
    ({"occlusion_position": 0.03, "hole_pair_spacing": 0.01, "hole_pair_rotation": 0}, "field_figures.0",
     "must select exactly one design point, selects 0"),
])
def test_field_figure_points_are_refused_in_one_line_unless_they_select_one_point(entry, key, message):
    """design_studies.<study>.field_figures: each entry names study parameters and selects exactly one point."""
    overlay = yaml.safe_load((REPO / "config" / "designs" / "occlusion_holes.yaml").read_text())
    overlay["design_studies"]["occlusion_holes"]["field_figures"] = [entry]
    with pytest.raises(ConfigError) as err:
        load_config(deep_merge(BASE, overlay))
    msg = str(err.value)
    assert "\n" not in msg and msg.startswith(f"config error: design_studies.occlusion_holes.{key}: {message}"), msg


def test_field_figure_points_need_field_files():
    """A point that writes no field files (fields.enabled false) has nothing to draw: refused, naming the entry."""
    overlay = yaml.safe_load((REPO / "config" / "designs" / "occlusion_holes.yaml").read_text())
    overlay["design_studies"]["occlusion_holes"]["base"]["fields"] = {"enabled": False}
    with pytest.raises(ConfigError) as err:
        load_config(deep_merge(BASE, overlay))
    assert str(err.value).startswith("config error: design_studies.occlusion_holes.field_figures.0: point ") and \
        "writes no field files (fields.enabled: false)" in str(err.value), err.value


# ------------------------------------------------------------------------------------------ escalation

def test_escalated_points_are_those_nearest_a_failing_corner():
    lo, hi = {"a": 0.0, "b": 0.0}, {"a": 2.0, "b": 1.0}
    corners = [{"a": a, "b": b} for a in (0.0, 2.0) for b in (0.0, 1.0)]
    points = [{"a": a, "b": b} for a in (0.0, 1.0, 2.0) for b in (0.0, 0.5, 1.0)]
    flags = rc.escalated(points, corners, [False, False, False, True], lo, hi)     # corner (2, 1) failed
    # nearest (range-scaled): (2, 1), (2, .5) and (1, 1) alone or tied, and the centre (1, .5), equidistant to all
    assert [p for p, f in zip(points, flags) if f] == [{"a": 1.0, "b": 0.5}, {"a": 1.0, "b": 1.0},
                                                       {"a": 2.0, "b": 0.5}, {"a": 2.0, "b": 1.0}]
    assert not any(rc.escalated(points, corners, [False] * 4, lo, hi))
    assert rc.nearest_corners({"a": 0.4, "b": 0.9}, corners, lo, hi) == [1]


def _escalating_study(tmp_path) -> tuple[dict, Path]:
    from helpers.design_runs import grid

    cfg = deep_merge(copy.deepcopy(BASE), MINI)
    cfg["design_studies"] = {"s": grid(model="2", hole_diameter=[5e-4, 6e-4, 7e-4], hole_pair_spacing=[0.005, 0.01])}
    cfg["design_studies"]["s"]["rung_check"] = {"corners": "all", "on_failure": "escalate"}
    path = tmp_path / "cfg.yaml"
    path.write_text(yaml.safe_dump(cfg, sort_keys=False))
    return cfg, path


def _write_check(path: Path, ok: list) -> None:
    ds = xr.Dataset({"corner_within_tolerance": ("corner", np.array(ok, np.int8))},
                    attrs={FORMAT_VERSION_ATTR: FORMAT_VERSION})
    ds.to_netcdf(path)


def test_a_failing_corner_escalates_its_region_in_the_job_plan(tmp_path):
    """Under on_failure: escalate the dataset's input function reads the rung check (a checkpoint): every corner
    within the tolerance, nothing more to run; one corner beyond it, its nearest points' fully coupled solves."""
    from helpers.design_runs import dry_run, pretend_done
    from helpers.snakemake_runs import ok, snakemake

    cfg, path = _escalating_study(tmp_path)
    st = studies(load_config(copy.deepcopy(cfg)))["s"]
    pretend_done(tmp_path, cfg, "s")
    check = tmp_path / "results/designs/s/rung_check.nc"
    _write_check(check, [1] * len(st.check.corners))
    os.utime(check, (1e9 + 2, 1e9 + 2))
    ok(snakemake(tmp_path, path, "--touch", "--cores", "1", "design_s", profile=None))
    assert dry_run(tmp_path, cfg, "design_s") == {}
    failing = [c.values == {"hole_diameter": 7e-4, "hole_pair_spacing": 0.01} for c in st.check.corners]
    _write_check(check, [int(not f) for f in failing])
    escalated = escalated_points(st, [int(not f) for f in failing])
    # the 3 x 2 grid: (7e-4, 0.01) and the middle diameter's (6e-4, 0.01), equidistant from its two corners
    assert sorted(st.point(p).values["hole_diameter"] for p in escalated) == [6e-4, 7e-4]
    assert {st.point(p).values["hole_pair_spacing"] for p in escalated} == {0.01}
    counts = dry_run(tmp_path, cfg, "design_s")
    assert counts == {"design_escalated_solve": 2, "design_dataset": 1, "design_figures": 1, "design_map": 1,
                      "design_s": 1}, counts


def test_an_escalating_study_plans_every_point_before_its_rung_check(tmp_path):
    """The dataset's inputs wait for the checkpoint, but design_<study> asks for every point's and reference's run:
    a dry run of stricture_holes lists them all (18 + 2), its 8 corners' fully coupled solves (the corners are grid
    points: their one-way runs serve), one wall motion per stricture position and the stented reference, and the
    field figures of its field_figures point."""
    from helpers.design_runs import dry_run

    cfg = deep_merge(copy.deepcopy(BASE), yaml.safe_load((REPO / "config/designs/stricture_holes.yaml").read_text()))
    counts = dry_run(tmp_path, cfg, "design_stricture_holes")
    assert counts == {"design_mesh": 20, "design_wall_motion": 4, "design_solve": 20, "design_corner_solve": 8,
                      "design_rung_check": 1, "design_dataset": 1, "design_figures": 1, "design_map": 1,
                      "design_passage": 1, "design_field_hole_flow": 1, "design_field_stent_wss": 1,
                      "design_stricture_holes": 1}, counts


def test_the_dataset_records_the_rung_of_each_point(tmp_path):
    from helpers.design_runs import fake_run, stamp, stamp_corners

    cfg, _ = _escalating_study(tmp_path)
    cfg = load_config(cfg)
    st = studies(cfg)["s"]
    corners = {}
    for c in st.check.corners:
        corners[c.id] = (tmp_path / f"{c.id}_rung.nc", tmp_path / f"{c.id}_ref.nc")
        bad = c.values["hole_diameter"] == 7e-4 and c.values["hole_pair_spacing"] == 0.01
        fake_run(corners[c.id][0], 1e-9 * (1.2 if bad else 1.0), 1e-5)
        fake_run(corners[c.id][1], 1e-9, 1e-5)
    paths = {}
    for p in st.points:
        paths[p.id] = tmp_path / f"{p.id}.nc"
        fake_run(paths[p.id], 1e-9, 1e-5)
    check = rc_dataset(cfg, stamp_corners(st, corners))
    ds = study_dataset(cfg, "s", stamp(st, paths), check)
    rung = ds["rung"].transpose("hole_diameter", "hole_pair_spacing").values
    assert rung.tolist() == [["one_way", "one_way"], ["one_way", "fully_coupled"], ["one_way", "fully_coupled"]]
    assert json.loads(ds.attrs["escalated_points"]) == escalated_points(st, check["corner_within_tolerance"].values)
    assert ds["rung"].attrs["long_name"] == metadata.VARIABLES["rung"][1]


def rc_dataset(cfg, corners):
    from ureterfsi.designs.results import rung_check_dataset

    return rung_check_dataset(cfg, "s", corners)


# ------------------------------------------------------------------------------------------ the dataset

def _passage_run(path: Path, hole_z, up: float, lumen_share: float, pelvic: float) -> None:
    """A run file of a stented, obstructed point: holes at `hole_z` (one recorded per pair, the quarter model), the
    upstream ones taking in `up` (m^3/s, into the stent), the others giving it out; the plane of the obstruction
    carrying 1e-8 m^3/s, `lumen_share` of it in the stent; the pelvis at `pelvic` Pa."""
    t = np.linspace(0.0, 0.04, 3)
    z = np.asarray(hole_z, float)
    flux = np.where(z[:, None] < 0.005, -up, up) * np.ones((z.size, t.size))
    one = np.ones(t.size)
    ds = xr.Dataset({"outlet_flux": ("time", 1e-8 * one), "inlet_flux": ("time", 1e-8 * one),
                     "outlet_lumen_flux": ("time", 5e-9 * one), "inlet_lumen_flux": ("time", 5e-9 * one),
                     "max_wall_displacement": ("time", 1e-5 * one), "min_ale_jacobian": ("time", one),
                     "obstruction_flux": ("time", 1e-8 * one),
                     "obstruction_lumen_flux": ("time", lumen_share * 1e-8 * one),
                     "pelvic_pressure": ("time", pelvic * one), "hole_flux": (("hole", "time"), flux),
                     **{k: ("hole", np.full(z.size, v)) for k, v in (
                         ("hole_wall_tawss", 0.05), ("hole_wall_osi", 0.1), ("hole_wall_low_wss_area_fraction", 0.2),
                         ("hole_gross_exchange_volume", 1e-10), ("hole_net_volume", 4e-11), ("hole_active", 1.0))}},
                    coords={"time": ("time", t), "hole_z": ("hole", z), "hole_side": ("hole", np.ones(z.size)),
                            "hole_axis": ("hole", np.ones(z.size))},
                    attrs={"wall_time_s": 3.0, "config_hash": "x"})
    metadata.annotate(ds)
    ds.attrs[FORMAT_VERSION_ATTR] = FORMAT_VERSION
    ds.to_netcdf(path)


def mini_occlusion_config(tmp_path) -> dict:
    from helpers.snakemake_runs import e2e_config

    overlay = yaml.safe_load((REPO / "tests" / "overlays" / "occlusion-holes-mini.yaml").read_text())
    return deep_merge(e2e_config(tmp_path / "base.yaml"), overlay)


def test_a_run_made_under_another_configuration_is_refused(tmp_path):
    """The runs of the 2 x 2 study made, then its base changed (the bladder's filling pressure) and Snakemake told to
    rerun on mtime alone, which keeps them: the dataset refuses the first point's run in one line, naming the file,
    rather than mixing two configurations; a one-way solver key (which no fully coupled solve reads) does not."""
    from helpers.design_runs import stamp
    from ureterfsi.data.checked import BadFile

    raw = mini_occlusion_config(tmp_path)
    st = studies(load_config(raw))["occlusion_mini"]
    paths = {}
    for i, p in enumerate(st.points + st.references):
        paths[p.id] = tmp_path / f"{p.id}.nc"
        _passage_run(paths[p.id], [0.00125, 0.00875], 2e-9, 0.999, 1100.0 + i)
    stamp(st, paths)
    other = copy.deepcopy(raw)
    other.setdefault("solver", {})["one_way_reuse_contraction"] = 0.5
    assert study_dataset(load_config(other), "occlusion_mini", paths).sizes["reference"] == 2
    other["design_studies"]["occlusion_mini"]["base"]["ends"]["bladder"]["filling_pressure"] = 1200.0
    with pytest.raises(BadFile) as err:
        study_dataset(load_config(other), "occlusion_mini", paths)
    first = st.points[0].id
    assert str(err.value).startswith(f"{paths[first]}: made under another configuration than design point "
                                      f"occlusion_mini/{first}'s on the fully_coupled rung (config_hash "), err.value
    assert "\n" not in str(err.value) and str(err.value).endswith(f"re-run it (snakemake --forcerun {paths[first]})")


def test_passage_quantities_of_the_dataset_pass_the_cf_checker(tmp_path):
    """Per point the obstruction and its centre, per hole upstream or not, the lumen share past the obstruction,
    the references on their dimension; every variable in the registry; CF 1.8 (compliance-checker)."""
    from helpers.cf_check import cf_errors
    from helpers.design_runs import stamp

    cfg = load_config(mini_occlusion_config(tmp_path))
    st = studies(cfg)["occlusion_mini"]
    paths = {}
    for i, p in enumerate(st.points + st.references):
        paths[p.id] = tmp_path / f"{p.id}.nc"
        _passage_run(paths[p.id], [0.00125, 0.00875], 2e-9, 0.999, 1100.0 + i)
    ds = study_dataset(cfg, "occlusion_mini", stamp(st, paths))
    assert ds["obstruction_lumen_fraction"].dims == ("occlusion_position", "hole_pair_rotation")
    assert np.allclose(ds["obstruction_lumen_fraction"].values, 0.999)
    assert (ds["obstruction"].values == "occlusion").all()
    assert np.allclose(ds["obstruction_position"].transpose("occlusion_position", ...).values[:, 0], [0.0045, 0.0055])
    assert ds["hole_proximal"].dims == ("occlusion_position", "hole_pair_rotation", "hole")
    assert (ds["hole_proximal"].values[..., 0] == 1).all() and (ds["hole_proximal"].values[..., 1] == 0).all()
    assert list(ds["reference"].values) == ["unstented", "stented"] and list(ds["reference_model"].values) == [1, 2]
    assert np.allclose(ds["reference_peak_pelvic_pressure"].values, [1104.0, 1105.0])
    assert set(f"reference_{q}" for q in REFERENCE_SCALARS) <= set(ds.variables)
    assert (ds["rung"].values == "fully_coupled").all() and ds.attrs["rung_check"].startswith("not checked")
    for name, var in ds.variables.items():
        assert var.attrs.get("units") and var.attrs.get("long_name"), name
    path = tmp_path / "occlusion_mini.nc"
    metadata.write_netcdf(ds, path)
    errors, warnings = cf_errors(path)
    report = json.loads(Path(str(path) + ".cc.json").read_text())["cf:1.8"]
    assert errors == 0, report["high_priorities"]
    assert warnings == 0, [r for r in report["medium_priorities"] if r["msgs"]]


# ------------------------------------------------------------------------------------------ end to end

def test_fully_coupled_design_solves_reserve_the_partitioned_entry(tmp_path):
    """A dry run of the 2 x 2 occlusion study: its 3D solves (partitioned sweeps, the study's overlay; the global
    configuration solves by Newton on the whole system) reserve study.memory_mb.partitioned, not the whole-system
    entry, so that two run side by side; its r-z reference reserves `axisymmetric`."""
    from helpers.snakemake_runs import ok, planned_jobs, snakemake

    cfg = mini_occlusion_config(tmp_path)
    path = tmp_path / "cfg.yaml"
    path.write_text(yaml.safe_dump(cfg, sort_keys=False))
    jobs = [j for j in planned_jobs(ok(snakemake(tmp_path, path, "-n", "-p", "design_occlusion_mini", profile=None)))
            if j["rule"] == "design_solve"]
    table = cfg["study"]["memory_mb"]
    assert cfg["solver"]["fully_coupled_scheme"] == "monolithic"
    reserved = sorted(int(j["resources"]["mem_mb"]) for j in jobs)
    assert reserved == [table["axisymmetric"]] + 5 * [table["partitioned"]["coarse"]], reserved


def test_two_by_two_occlusion_study_end_to_end(tmp_path):
    """tests/overlays/occlusion-holes-mini.yaml: occlusion position (4.5, 5.5 mm) x hole-pair arrangement on the 10 mm
    segment, fully coupled by the partitioned sweeps under the radial load (as the study), the pelvis filled at
    1 mL/min and the bladder at its filling pressure, two steps of 20 ms, with the unstented and the stented unobstructed references: configuration -> meshes -> solves -> dataset ->
    figures. The physics: the annulus is closed at the occlusion, so the stent lumen carries the flow past it; the
    production enters the stent through the hole upstream and leaves it through the one downstream; the pelvis
    stands above the bladder. The dataset passes the CF checker."""
    from helpers.snakemake_runs import job_counts, ok, snakemake

    cfg = mini_occlusion_config(tmp_path)
    path = tmp_path / "cfg.yaml"
    path.write_text(yaml.safe_dump(cfg, sort_keys=False))
    counts = job_counts(ok(snakemake(tmp_path, path, "--cores", "2", "design_occlusion_mini", timeout=5400)))
    assert counts == {"design_mesh": 6, "design_solve": 6, "design_dataset": 1, "design_figures": 1,
                      "design_map": 1, "design_passage": 1, "design_field_hole_flow": 1, "design_field_stent_wss": 1,
                      "design_occlusion_mini": 1}, counts
    check_occlusion_study(tmp_path, cfg)


def check_occlusion_study(work: Path, cfg: dict) -> None:
    """The assertions of test_two_by_two_occlusion_study_end_to_end on a finished run in `work`."""
    from helpers.cf_check import cf_errors

    dataset = work / "results/designs/occlusion_mini.nc"
    with xr.open_dataset(dataset, decode_times=False) as ds:
        ds.load()
    print("\n2x2 occlusion study:", {q: ds[q].values.round(12).tolist() for q in (
        "obstruction_lumen_fraction", "hole_net_volume", "hole_gross_exchange_volume", "hole_wall_tawss",
        "hole_wall_low_wss_area_fraction", "peak_pelvic_pressure", "stent_lumen_fraction", "wall_time")},
          {q: ds[q].values.round(12).tolist() for q in ds.data_vars if q.startswith("reference_")})
    assert ds["obstruction_lumen_fraction"].dims == ("occlusion_position", "hole_pair_rotation")
    assert (ds["obstruction_lumen_fraction"].values > 0.9).all()
    # the initial steady state drains the production (docs/end-conditions.md): what enters passes the occlusion,
    # all of it in the lumen (the flux through the plane is consistent with the continuity rows)
    production = cfg["ends"]["kidney"]["urine_production"]
    for q in ("inlet_flux", "obstruction_flux", "obstruction_lumen_flux"):
        np.testing.assert_allclose(ds[q].isel(time=0).values, production, rtol=1e-4, err_msg=q)
    up = ds["hole_proximal"].values == 1
    assert up.sum(axis=-1).tolist() == [[1, 1], [1, 1]] and (ds["hole_proximal"].values[~up] == 0).all()
    net = ds["hole_net_volume"].values                    # positive out of the stent
    assert (net[up] < 0).all() and (net[~up] > 0).all(), net
    gross = ds["hole_gross_exchange_volume"].values
    assert (gross >= np.abs(net) * (1 - 1e-9)).all()
    for q in ("hole_wall_tawss", "hole_wall_low_wss_area_fraction"):
        assert np.isfinite(ds[q].values).all() and (ds[q].values >= 0).all(), q
    # the end faces' normal stress: p_ref + the bladder's filling pressure (gauge) at the outlet
    bladder = cfg["fluid"]["reference_pressure"] + cfg["ends"]["bladder"]["filling_pressure"]
    assert (ds["peak_pelvic_pressure"].values > bladder).all()
    assert (ds["rung"].values == "fully_coupled").all()
    assert list(ds["reference"].values) == ["unstented", "stented"]
    # the references: the unstented junction is a valve (its forward drop above the bladder); the stent holds it
    # open and nothing obstructs, so the pelvis stands at the bladder's pressure; the occlusion raises it above that
    ref = dict(zip(ds["reference"].values, ds["reference_peak_pelvic_pressure"].values))
    assert ref["unstented"] > bladder and abs(ref["stented"] - bladder) < 1.0, ref
    assert (ds["peak_pelvic_pressure"].values > ref["stented"] + 1.0).all()
    for name, var in ds.variables.items():
        assert var.attrs.get("units") and var.attrs.get("long_name"), name
    errors, warnings = cf_errors(dataset)
    report = json.loads(Path(str(dataset) + ".cc.json").read_text())["cf:1.8"]
    assert errors == 0, report["high_priorities"]
    assert warnings == 0, [r for r in report["medium_priorities"] if r["msgs"]]
    for kind in ("parameters", "map", "passage"):
        for ext in cfg["figures"]["formats"]:
            assert (work / f"results/figures/designs/occlusion_mini_{kind}.{ext}").stat().st_size > 0, kind
    # the field figures of the point field_figures selects: the occlusion at 4.5 mm, the pairs rotated
    st = studies(load_config(cfg))["occlusion_mini"]
    assert st.point(st.field_points[0]).values == {"occlusion_position": 0.0045, "hole_pair_rotation": 90}
    for kind in ("field_hole_flow", "field_stent_wss"):
        for ext in cfg["figures"]["formats"]:
            path = work / f"results/figures/designs/occlusion_mini_{st.field_points[0]}_{kind}.{ext}"
            assert path.stat().st_size > 0, path
