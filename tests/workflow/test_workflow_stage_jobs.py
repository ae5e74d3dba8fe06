"""What the stability and design rules ask of the package (ureterfsi.stability.jobs, ureterfsi.designs.jobs) and the
cluster cap of a rule's resource (ureterfsi.workflow.cluster): plain functions, without Snakemake's DAG."""
import json
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

from ureterfsi.config import load_config_files
from ureterfsi.data.provenance import FORMAT_VERSION, FORMAT_VERSION_ATTR
from ureterfsi.designs import jobs as design_jobs
from ureterfsi.designs.expand import studies
from ureterfsi.designs.passage import escalated_points
from ureterfsi.stability import cases
from ureterfsi.stability import jobs as stability_jobs
from ureterfsi.workflow import paths

REPO = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="module")
def cfg():
    """hole_diameter_spacing with its corners on the 10 mm segment (a segment of their own: their meshes and wall
    motion beside the points')."""
    out = load_config_files([REPO / "config/config.yaml", REPO / "config/designs/hole_diameter_spacing.yaml"])
    out["design_studies"]["hole_diameter_spacing"]["rung_check"]["segment"] = "config/segment-10mm.yaml"
    return out


def test_stability_case_mesh_rung_and_trigger(cfg):
    names = {c.axis: c.name for c in cases(cfg)}
    rz, holes, level = names["bulk_ratio"], names["hole_elements"], names["mesh_level"]
    st = cfg["stability"]
    assert stability_jobs.case_mesh(cfg, rz) == paths.mesh("axisymmetric", st["model"], st["level"])
    assert stability_jobs.case_mesh(cfg, holes) == []                     # the case builds its own mesh
    assert stability_jobs.case_rung(cfg, rz) == ("fully_coupled", "axisymmetric", st["level"])
    assert stability_jobs.case_rung(cfg, holes) == ("one_way", st["holes"]["symmetry"], st["level"])
    assert stability_jobs.case_rung(cfg, level)[2] != st["level"]         # the mesh_level axis: its own level
    trigger = json.loads(stability_jobs.case_trigger(cfg, rz))
    assert trigger["axis"] == "bulk_ratio" and "axes" not in trigger["stability"] and "mesh" not in trigger
    assert "mesh" in json.loads(stability_jobs.case_trigger(cfg, holes))
    # plotting options do not enter a case, every section it reads does
    other = json.loads(json.dumps(cfg))
    other["figures"]["dpi"] += 1
    assert stability_jobs.case_trigger(other, rz) == stability_jobs.case_trigger(cfg, rz)
    other["time"]["dt"] *= 2
    assert stability_jobs.case_trigger(other, rz) != stability_jobs.case_trigger(cfg, rz)


def test_design_meshes_walls_inputs_and_figures(cfg, tmp_path):
    designs = studies(cfg)
    st = designs["hole_diameter_spacing"]
    meshes, walls = design_jobs.meshes(designs), design_jobs.walls(designs)
    # 9 points on 9 meshes, 4 corners on the segment on 4 more; one wall motion for the points, one for the corners
    assert (len(meshes), len(walls)) == (13, 2)
    assert json.loads(design_jobs.mesh_trigger(*meshes[st.points[0].mesh_id]))["symmetry"] == st.points[0].symmetry
    assert design_jobs.dataset_inputs(st) == {"runs": [paths.design_run(st.name, p.id) for p in st.points],
                                              "check": paths.rung_check(st.name)}
    assert len(design_jobs.corner_runs(st)) == 2 * len(st.check.corners)
    c = st.check.corners[0]
    assert "wall" not in design_jobs.corner_inputs(st, c.id, "fully_coupled")
    assert design_jobs.rung(design_jobs.corner_solve(st, c.id, "fully_coupled")) == ("fully_coupled", c.symmetry,
                                                                                     st.level)
    assert design_jobs.figures(st, ["png"]) == [paths.design_figure(st.name, k, "png") for k in ("parameters", "map")]
    # the caption before the dataset exists, then its attribute
    path = tmp_path / "d.nc"
    assert design_jobs.rung_check_caption(path).startswith("measured when")
    xr.Dataset(attrs={"rung_check": "within 0.05"}).to_netcdf(path)
    assert design_jobs.rung_check_caption(path) == "within 0.05"


def test_design_references_and_escalation(tmp_path):
    """stricture_holes: its references' meshes on their own models, every run asked up front, and the dataset's runs
    once the rung check is made: the escalated points' fully coupled runs in place of their one-way ones."""
    cfg = load_config_files([REPO / "config/config.yaml", REPO / "config/designs/stricture_holes.yaml"])
    st = studies(cfg)["stricture_holes"]
    meshes = design_jobs.meshes({st.name: st})
    unstented = next(r for r in st.references if r.name == "unstented")
    assert json.loads(design_jobs.mesh_trigger(*meshes[unstented.mesh_id]))["model"] == cfg["models"]["1"]
    one_way = [p.id for p in st.points + st.references if p.rung == "one_way"]
    assert set(design_jobs.walls({st.name: st})) == {p.wall_id for p in st.points + st.references if p.wall_id}
    assert len(one_way) == len(st.points) + 1
    assert design_jobs.escalates(st)
    ids = [p.id for p in st.points + st.references]
    assert design_jobs.runs(st) == [paths.design_run(st.name, i) for i in ids]
    assert design_jobs.dataset_inputs(st)["runs"] == design_jobs.runs(st)       # before the check is made
    ok = np.ones(len(st.check.corners), np.int8)
    ok[0] = 0
    check = tmp_path / "rung_check.nc"
    attrs = {FORMAT_VERSION_ATTR: FORMAT_VERSION}
    xr.Dataset({"corner_within_tolerance": ("corner", ok)}, attrs=attrs).to_netcdf(check)
    escalated = escalated_points(st, ok)
    assert 0 < len(escalated) < len(st.points)
    runs = design_jobs.dataset_inputs(st, check)
    assert runs["check"] == paths.rung_check(st.name)
    assert runs["runs"] == [paths.escalated_run(st.name, i) if i in escalated else paths.design_run(st.name, i)
                            for i in ids]


def test_cluster_cap_of_a_resource():
    from snakemake.resources import Resource

    from ureterfsi.workflow.cluster import capped

    def evaluated(resource):
        return resource.evaluate({}, input=[], attempt=1, threads=1, rulename="r", async_run=None).value

    assert evaluated(capped(Resource("tasks", 32), 8)) == 8
    assert evaluated(capped(Resource("tasks", 4), 8)) == 4
    assert evaluated(capped(Resource("mem_mb", lambda w: 64000), 48000)) == 48000
    assert evaluated(capped(Resource("slurm_extra", "x"), 8)) == "x"
