"""Corrupt or foreign pipeline files fail with one line `<path>: <what is wrong>`."""
from __future__ import annotations

import json
import runpy
from types import SimpleNamespace

import numpy as np
import pytest
import xarray as xr
from mpi4py import MPI

from helpers.synthetic import synthetic_run
from ureterfsi.analyses import aggregate
from ureterfsi.data.checked import MESH_SIDECAR, BadFile, read_json
from ureterfsi.config import load_config_files
from ureterfsi.mesh.build import build_mesh
from ureterfsi.mesh.io import load_mesh
from ureterfsi.data.provenance import FORMAT_VERSION_ATTR


def _one_line(err, path, what):
    msg = str(err.value)
    assert "\n" not in msg and msg.startswith(f"{path}: "), msg
    assert what in msg, msg
    return msg


@pytest.fixture
def run_file(tmp_path, cfg):
    p = tmp_path / "model2_coarse.nc"
    synthetic_run(cfg, "2", end=0.5).to_netcdf(p)
    return p


def test_truncated_run_file_to_aggregate(run_file, cfg):
    run_file.write_bytes(run_file.read_bytes()[:4000])
    with pytest.raises(BadFile) as err:
        aggregate.combine_models([run_file], cfg)
    _one_line(err, run_file, "truncated or corrupt netCDF")


def test_foreign_files_to_aggregate(tmp_path, run_file, cfg):
    text = tmp_path / "text.nc"
    text.write_text("model,flux\n1,2\n")
    empty = tmp_path / "empty.nc"
    empty.write_bytes(b"")
    with pytest.raises(BadFile) as err:
        aggregate.open_run(text)
    _one_line(err, text, "not a netCDF file")
    with pytest.raises(BadFile) as err:
        aggregate.open_run(empty)
    _one_line(err, empty, "empty run file (0 bytes)")
    with pytest.raises(BadFile) as err:
        aggregate.open_run(tmp_path / "absent.nc")
    _one_line(err, tmp_path / "absent.nc", "no such run file")
    foreign = tmp_path / "foreign.nc"
    xr.Dataset({"outlet_flux": ("time", np.zeros(3))}).to_netcdf(foreign)
    with pytest.raises(BadFile) as err:
        aggregate.open_run(foreign)
    _one_line(err, foreign, f"without attribute '{FORMAT_VERSION_ATTR}'")
    ds = xr.load_dataset(run_file, decode_times=False)
    no_model, old_format = ds.copy(), ds.copy()
    del no_model.attrs["model"]
    old_format.attrs[FORMAT_VERSION_ATTR] = 99
    for d, what in ((no_model, "missing attribute 'model' of a run file"), (old_format, "in file format 99"),
                    (ds.drop_vars("outlet_flux"), "missing variable 'outlet_flux' of a run file")):
        p = tmp_path / f"bad{len(what)}.nc"
        d.to_netcdf(p)
        with pytest.raises(BadFile) as err:
            aggregate.combine_models([p], cfg)
        _one_line(err, p, what)


def test_truncated_dataset_to_a_figure_script(tmp_path, repo_root, capsys):
    ds_path, log = tmp_path / "models_coarse.nc", tmp_path / "fig04.log"
    xr.Dataset({"x": ("t", np.zeros(100))}).to_netcdf(ds_path)
    ds_path.write_bytes(ds_path.read_bytes()[:3000])
    smk = SimpleNamespace(rule="fig04_outlet_flow", input=SimpleNamespace(models=str(ds_path)),
                          output=[str(tmp_path / "f.png")], params=SimpleNamespace(figures={"dpi": 50}),
                          log=[str(log)], config={})
    with pytest.raises(SystemExit) as ex:
        runpy.run_path(str(repo_root / "workflow/scripts/plot_figure.py"), init_globals={"snakemake": smk})
    assert ex.value.code == 1
    err = capsys.readouterr().err.strip()
    assert err.startswith(f"rule fig04_outlet_flow: {ds_path}: truncated or corrupt netCDF") and "\n" not in err
    text = log.read_text()
    assert f"{ds_path}: truncated or corrupt netCDF" in text and "Traceback" not in text


@pytest.fixture(scope="module")
def rz_mesh(tmp_path_factory, repo_root):
    d = tmp_path_factory.mktemp("rz")
    cfg = load_config_files([repo_root / "config/config.yaml", repo_root / "config/segment-10mm.yaml"])
    build_mesh(cfg, "1", "coarse", "axisymmetric", d / "m.msh", d / "m.json")
    return d / "m.msh", d / "m.json"


def test_truncated_or_foreign_mesh(rz_mesh, tmp_path):
    msh, side = rz_mesh
    data = msh.read_bytes()
    cases = {"truncated.msh": (data[: len(data) // 2], "truncated gmsh mesh"),
             "text.msh": (b"hello\n", "not a gmsh mesh"),
             "empty.msh": (b"", "empty gmsh mesh (0 bytes)"),
             "v2.msh": (b"$MeshFormat\n2.2 0 8\n$EndMeshFormat\n", "gmsh mesh format 2.2, expected 4.1"),
             "cut.msh": (data[: len(data) // 2] + b"\n$EndElements\n", "gmsh cannot read this mesh")}
    for name, (content, what) in cases.items():
        p = tmp_path / name
        p.write_bytes(content)
        with pytest.raises(BadFile) as err:
            load_mesh(p, MPI.COMM_WORLD)
        _one_line(err, p, what)
    mesh, ct, ft = load_mesh(msh, MPI.COMM_WORLD)     # the intact mesh still loads
    assert mesh.topology.index_map(2).size_global > 0


def test_bad_sidecar(rz_mesh, tmp_path):
    _, side = rz_mesh
    info = read_json(side, MESH_SIDECAR)
    assert info["model"] == "1"
    cut = tmp_path / "cut.json"
    cut.write_text(side.read_text()[:50])
    with pytest.raises(BadFile) as err:
        read_json(cut, MESH_SIDECAR)
    _one_line(err, cut, "not valid JSON (line")
    nokey = tmp_path / "nokey.json"
    nokey.write_text(json.dumps({k: v for k, v in info.items() if k != "hole_pair_z"}))
    with pytest.raises(BadFile) as err:
        read_json(nokey, MESH_SIDECAR)
    _one_line(err, nokey, "missing key 'hole_pair_z' of a mesh sidecar")
    lst = tmp_path / "list.json"
    lst.write_text("[1, 2]")
    with pytest.raises(BadFile) as err:
        read_json(lst, MESH_SIDECAR)
    _one_line(err, lst, "a JSON list")


# ------------------------------------------------------------------------------------ checkpoint identity
def test_checkpoint_of_another_load_is_not_resumed(rz_mesh, tmp_path, repo_root, monkeypatch, caplog):
    """A run with peak_traction 5e4 stopped after its first checkpoint, then the same
    target with 1e5: the stale checkpoint is set aside, the run starts at t = 0 and equals a clean 1e5 run."""
    import logging

    from ureterfsi.fsi import TimeIntegrator
    from ureterfsi.study.coupled import run
    from ureterfsi.study.options import RunSpec

    msh, _ = rz_mesh
    base = load_config_files([repo_root / "config/config.yaml", repo_root / "config/segment-10mm.yaml"])
    base["time"]["checkpoint_interval"] = 1
    low, high = json.loads(json.dumps(base)), json.loads(json.dumps(base))
    low["peristalsis"]["peak_traction"], high["peristalsis"]["peak_traction"] = 5e4, 1e5
    spec = RunSpec("1", "coarse", "axisymmetric", str(msh), end=0.04)
    ckpt = tmp_path / "ckpt" / "model1.npz"

    save = TimeIntegrator.save_checkpoint

    def save_then_stop(self, step, dt_next):
        save(self, step, dt_next)
        raise KeyboardInterrupt("stopped after the first checkpoint")

    monkeypatch.setattr(TimeIntegrator, "save_checkpoint", save_then_stop)
    with pytest.raises(KeyboardInterrupt):
        run(low, spec, str(tmp_path / "low.nc"), str(ckpt))
    monkeypatch.setattr(TimeIntegrator, "save_checkpoint", save)
    assert (ckpt.parent / "model1.rank0of1.npz").exists()

    with caplog.at_level(logging.INFO, logger="ureterfsi"):
        resumed = run(high, spec, str(tmp_path / "high.nc"), str(ckpt))
    lines = [r.getMessage() for r in caplog.records if "not resumed" in r.getMessage()]
    assert len(lines) == 1 and "written by another run (peristalsis.peak_traction 50000.0 -> 100000.0)" in lines[0]
    assert "starting from t = 0" in lines[0] and "resumed from checkpoint" not in caplog.text
    assert len(list(ckpt.parent.glob("model1.rank0of1.stale-*.npz"))) == 1
    clean = run(high, spec, str(tmp_path / "clean.nc"))
    assert resumed["time"].values[0] == 0.0
    for name in ("max_wall_displacement", "outlet_flux", "wall_radial_displacement"):
        np.testing.assert_allclose(resumed[name].values, clean[name].values, rtol=1e-10, atol=1e-20, err_msg=name)
    # the same configuration does resume, and gives the clean run
    monkeypatch.setattr(TimeIntegrator, "save_checkpoint", save_then_stop)
    with pytest.raises(KeyboardInterrupt):
        run(high, spec, str(tmp_path / "again.nc"), str(ckpt))
    monkeypatch.setattr(TimeIntegrator, "save_checkpoint", save)
    caplog.clear()
    with caplog.at_level(logging.INFO, logger="ureterfsi"):
        again = run(high, spec, str(tmp_path / "again.nc"), str(ckpt))
    assert "resumed from checkpoint: step 1" in caplog.text and "not resumed" not in caplog.text
    np.testing.assert_allclose(again["max_wall_displacement"].values, clean["max_wall_displacement"].values,
                               rtol=1e-10, atol=1e-20)


def test_solve_of_a_truncated_mesh_is_one_line_on_stderr(rz_mesh, tmp_path, repo_root, capsys):
    from ureterfsi.study.cli import main

    msh, _ = rz_mesh
    cut = tmp_path / "cut.msh"
    cut.write_bytes(msh.read_bytes()[:5000])
    code = main(["--config", str(repo_root / "config/config.yaml"), str(repo_root / "config/segment-10mm.yaml"),
                 "--model", "1", "--level", "coarse", "--symmetry", "axisymmetric", "--mesh", str(cut),
                 "--out", str(tmp_path / "out.nc")])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 1 and err[-1] == f"{cut}: truncated gmsh mesh (does not end with a closing '$End...' section tag)"
    assert not (tmp_path / "out.nc").exists()


def test_snakemake_rule_log_gets_the_line(tmp_path, repo_root):
    """End to end through Snakemake: a figure rule fed a truncated dataset fails, its log holds the line."""
    import subprocess
    import sys
    from pathlib import Path

    bad = tmp_path / "models_coarse.nc"
    xr.Dataset({"x": ("t", np.zeros(100))}).to_netcdf(bad)
    bad.write_bytes(bad.read_bytes()[:3000])
    (tmp_path / "Snakefile").write_text(
        "rule fig04_outlet_flow:\n"
        f"    input: models='{bad}'\n"
        "    output: 'fig04.png'\n"
        "    params: figures={'dpi': 50}\n"
        "    log: 'fig04.log'\n"
        f"    script: '{repo_root}/workflow/scripts/plot_figure.py'\n")
    snakemake = Path(sys.executable).with_name("snakemake")
    proc = subprocess.run([str(snakemake), "--cores", "1", "-s", "Snakefile"], cwd=tmp_path, capture_output=True,
                          text=True, timeout=300)
    assert proc.returncode != 0
    text = (tmp_path / "fig04.log").read_text()
    assert f"{bad}: truncated or corrupt netCDF" in text and "Traceback" not in text, text
    assert f"rule fig04_outlet_flow: {bad}: truncated or corrupt netCDF" in proc.stderr


# ------------------------------------------------------------------------------- holes found by the catalogue
def test_mesh_of_another_model_or_symmetry(rz_mesh, tmp_path):
    """The r-z mesh of model 1 handed to a 3D stented run (and back): one line naming the file, not a
    ValueError from the operators deep in the solve."""
    msh, _ = rz_mesh
    with pytest.raises(BadFile) as err:
        load_mesh(msh, MPI.COMM_WORLD, expect=("quarter", True, "model 2 (quarter)"))
    _one_line(err, msh, "a 2D mesh without stent cells, but model 2 (quarter) needs a 3D mesh with stent cells")
    mesh, _, _ = load_mesh(msh, MPI.COMM_WORLD, expect=("axisymmetric", False, "model 1 (axisymmetric)"))
    assert mesh.geometry.dim == 2


def test_solve_of_a_directory_or_another_models_mesh_is_one_line(rz_mesh, tmp_path, repo_root, capsys):
    """A directory where the mesh should be (was: IsADirectoryError from hashing it for the checkpoint) and a
    mesh of the wrong dimension (was: ValueError 'axisymmetric scenes need a 2D (r, z) mesh')."""
    from ureterfsi.study.cli import main

    msh, _ = rz_mesh
    folder = tmp_path / "dir.msh"
    folder.mkdir()
    base = ["--config", str(repo_root / "config/config.yaml"), str(repo_root / "config/segment-10mm.yaml"),
            "--level", "coarse", "--out", str(tmp_path / "out.nc"), "--checkpoint", str(tmp_path / "ck.npz")]
    code = main(base + ["--model", "1", "--symmetry", "axisymmetric", "--mesh", str(folder)])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 1 and err[-1] == f"{folder}: is a directory, not a gmsh mesh", err
    code = main(base + ["--model", "2", "--symmetry", "quarter", "--mesh", str(msh)])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 1 and err[-1].startswith(f"{msh}: a 2D mesh without stent cells, but model 2 (quarter)"), err
    assert not (tmp_path / "out.nc").exists()


def test_converted_units_are_refused(tmp_path, run_file, cfg):
    """A run file whose flux was converted to ml/s, or whose time is in ms, is refused (was: aggregated silently,
    a 10^6 error in every flux)."""
    ds = xr.load_dataset(run_file, decode_times=False)
    for var, units, what in (("outlet_flux", "ml/s", "variable 'outlet_flux' of a run file in units 'ml/s', "
                                                     "expected 'm3 s-1'"),
                             ("time", "ms since 2000-01-01", "variable 'time' of a run file in units 'ms since")):
        bad = ds.copy()
        bad[var] = bad[var] * 1e3
        bad[var].attrs["units"] = units
        p = tmp_path / f"{var}.nc"
        bad.to_netcdf(p)
        with pytest.raises(BadFile) as err:
            aggregate.combine_models([p], cfg)
        _one_line(err, p, what)


def test_wall_motion_units(tmp_path):
    from ureterfsi.data.checked import open_netcdf
    from ureterfsi.data.cf import WALL_MOTION_VARIABLES, write_netcdf, attach
    from ureterfsi.data.provenance import FORMAT_VERSION
    from ureterfsi.study.oneway import WALL_MOTION

    names = [v for v in WALL_MOTION.variables if v not in ("time", "z_inner", "z_outer")]
    ds = xr.Dataset({v: (("z_inner", "time"), np.zeros((2, 3))) for v in names},
                    coords={"time": [0.0, 0.01, 0.02], "z_inner": [0.0, 1.0], "z_outer": [0.0, 1.0]})
    attach(ds, WALL_MOTION_VARIABLES)
    ds.attrs.update({FORMAT_VERSION_ATTR: FORMAT_VERSION, "wall_config_hash": "x"})
    good = tmp_path / "good.nc"
    write_netcdf(ds, good)
    open_netcdf(good, WALL_MOTION)
    ds["inner_radial_displacement"].attrs["units"] = "mm"
    bad = tmp_path / "mm.nc"
    write_netcdf(ds, bad)
    with pytest.raises(BadFile) as err:
        open_netcdf(bad, WALL_MOTION)
    _one_line(err, bad, "variable 'inner_radial_displacement' of a wall-motion file in units 'mm', expected 'm'")


def test_design_files_are_checked(tmp_path, run_file, cfg, repo_root, capsys):
    """The design dataset rule read its runs with a bare xarray call (truncated run: OSError in an empty log)
    and the design-figure rules their dataset so; both now go through checked_io and run_script."""
    from ureterfsi.designs.expand import studies
    from ureterfsi.designs.results import study_dataset
    from ureterfsi.config import load_config

    cfg = load_config(json.loads(json.dumps(cfg)), {"design_studies": {"s": {
        "model": "2", "level": "coarse", "grid": {"parameters": {"peak_traction": [5e4]}}}}})
    (point,) = studies(cfg)["s"].points
    run_file.write_bytes(run_file.read_bytes()[:3000])
    with pytest.raises(BadFile) as err:
        study_dataset(cfg, "s", {point.id: run_file})
    _one_line(err, run_file, "truncated or corrupt netCDF")
    bare = tmp_path / "s.nc"
    xr.Dataset({"x": ("t", np.zeros(3))}).to_netcdf(bare)
    log = tmp_path / "fig.log"
    smk = SimpleNamespace(rule="design_figures", input=[str(bare)], output=[str(tmp_path / "f.png")],
                          params=SimpleNamespace(dpi=50), log=[str(log)], config={})
    with pytest.raises(SystemExit) as ex:
        runpy.run_path(str(repo_root / "workflow/scripts/design_figures.py"), init_globals={"snakemake": smk})
    assert ex.value.code == 1
    err = capsys.readouterr().err.strip()
    assert err.startswith(f"rule design_figures: {bare}: design-study dataset without attribute") and "\n" not in err
    assert f"{bare}: design-study dataset without attribute" in log.read_text()


def test_corrupt_field_files_are_named(tmp_path):
    """The field figures read fields.json, the XDMF index and the HDF5 snapshots with bare json/XML/netCDF4
    calls: a truncated file ended in a JSONDecodeError/ParseError/OSError not naming it."""
    from ureterfsi.data import fieldfiles

    d = tmp_path / "model2_coarse"
    d.mkdir()
    (d / "fields.json").write_text('{"parts": {"domain": {"file": "domain.xd')
    with pytest.raises(BadFile) as err:
        fieldfiles.urine_fields(d)
    _one_line(err, d / "fields.json", "not valid JSON")
    (d / "domain.xdmf").write_text('<?xml version="1.0"?>\n<Xdmf Version="3.0"><Domain><Grid Name="x"')
    with pytest.raises(BadFile) as err:
        fieldfiles.read_fields(d, "domain")
    _one_line(err, d / "domain.xdmf", "not valid XDMF")
    h5 = d / "domain_s000001.h5"
    xr.Dataset({"f": ("n", np.zeros(1000))}).to_netcdf(h5)
    h5.write_bytes(h5.read_bytes()[:2000])
    with pytest.raises(BadFile) as err:
        fieldfiles._read(d, "domain_s000001.h5:/Function/f/0")
    _one_line(err, h5, "truncated or corrupt field file")
    with pytest.raises(BadFile) as err:
        fieldfiles._read(d, "domain_s000002.h5:/Function/f/0")
    _one_line(err, d / "domain_s000002.h5", "no such field file")


def test_checkpoint_whose_field_snapshots_are_gone_is_not_resumed(tmp_path):
    """A checkpoint resumed after its staged field snapshots were removed ended, after the last step, in a
    FileNotFoundError traceback (fields.FieldWriter.finish indexes every snapshot): now it is not resumed."""
    from ureterfsi.study.fields import FieldWriter

    fw = FieldWriter(tmp_path / "model1_coarse", [SimpleNamespace(name="domain")], [0.02], 0, MPI.COMM_WORLD)
    state = {"snapshots": [[1, 0.02]], "write_time": 0.1}
    assert fw.cannot_resume(state).startswith(f"its field snapshots are gone ({fw.stage / 'domain_mesh.xdmf'}")
    fw.stage.mkdir()
    for name in ("domain_mesh.xdmf", "domain_s000001.xdmf"):
        (fw.stage / name).write_text("<Xdmf/>")
    assert fw.cannot_resume(state) == "" and fw.cannot_resume({"snapshots": [], "write_time": 0}) == ""


def test_a_run_that_would_write_no_field_snapshot_is_refused_before_its_solve(cfg):
    """A run ending before the first probe time with fields.every_steps = 0 solved to its end and then failed in
    FieldWriter.finish: now field_writer refuses it at set-up, naming both keys."""
    from ureterfsi.study.fields import field_writer

    cfg["fields"] |= {"enabled": True, "every_steps": 0}
    cfg["time"]["probe_times"] = [0.5, 1.0]
    with pytest.raises(ValueError, match=r"no time.probe_times within the run's 0-0.3 s and fields.every_steps = 0"):
        field_writer(cfg, "unused.nc", lambda quantities: [], 0.3, MPI.COMM_WORLD)
    assert field_writer(cfg, "unused.nc", lambda quantities: [], 0.5, MPI.COMM_WORLD).times == [0.5]
    cfg["fields"]["every_steps"] = 10
    assert field_writer(cfg, "unused.nc", lambda quantities: [], 0.3, MPI.COMM_WORLD).times == []


def test_design_figures_of_a_stent_free_study():
    """A design study of a stent-free model has no holes (dimension hole of size 0): its parameters figure
    failed with 'cannot reshape array of size 0' (xarray cannot stack an empty dimension)."""
    from ureterfsi.plotting.designs import parameters_figure

    ds = xr.Dataset({"peak_outlet_flux": ("peak_traction", [1e-9, 2e-9]),
                     "peak_hole_flux": (("peak_traction", "hole"), np.zeros((2, 0)))},
                    coords={"peak_traction": [4e4, 5e4], "hole": np.zeros(0, dtype=int)})
    for v in ds.variables:
        ds[v].attrs["units"] = "1"
    fig = parameters_figure(ds)
    assert fig.axes


def test_run_of_another_level_or_model_is_named(tmp_path, cfg):
    """A run file of another mesh level among a level's runs (was: ValueError naming no file, traceback in the
    log), and of another model among a convergence study's levels."""
    a, b = tmp_path / "model1_coarse.nc", tmp_path / "model2_coarse.nc"
    synthetic_run(cfg, "1", end=0.5).to_netcdf(a)
    other = synthetic_run(cfg, "2", end=0.5)
    other.attrs["mesh_level"] = "fine"
    other.to_netcdf(b)
    with pytest.raises(BadFile) as err:
        aggregate.combine_models([a, b], cfg)
    _one_line(err, b, f"a run of mesh level 'fine', combined with level 'coarse' ({a})")
    c = tmp_path / "model3_medium.nc"
    third = synthetic_run(cfg, "3", end=0.5)
    third.attrs["mesh_level"] = "medium"
    third.to_netcdf(c)
    with pytest.raises(BadFile) as err:
        aggregate.combine_levels([b, c], 0.5, cfg)
    _one_line(err, c, f"a run of model 3, combined with model 2 ({b}): a convergence study is one model")


def test_run_of_another_rung_in_a_runs_place_is_named(tmp_path, cfg):
    """A one-way run copied into the fully coupled run's place (same model and level) was combined silently."""
    p = tmp_path / "fully_coupled" / "model2_coarse.nc"
    p.parent.mkdir()
    run = synthetic_run(cfg, "2", end=0.5)
    run.attrs.update(fidelity="one_way", symmetry="quarter")
    run.to_netcdf(p)
    expect = {str(p): {"model": "2", "mesh_level": "coarse", "fidelity": "fully_coupled", "symmetry": "quarter"}}
    with pytest.raises(BadFile) as err:
        aggregate.combine_models([p], cfg, expect=expect)
    _one_line(err, p, "a run of model 2, mesh_level coarse, fidelity one_way, symmetry quarter, but this file is "
                      "the run of model 2, mesh_level coarse, fidelity fully_coupled, symmetry quarter")
    expect[str(p)]["fidelity"] = "one_way"
    assert aggregate.combine_models([p], cfg, expect=expect).sizes["model"] == 1


def test_atomically_written_files_get_the_umasks_permissions(tmp_path):
    """Results written through a temporary file are readable as a plain open() would leave them (mkstemp's
    0600 would hide them from a group sharing a cluster's project directory); a failed block leaves nothing."""
    import os
    import stat

    from ureterfsi.data.provenance import atomic_path, write_json
    old = os.umask(0o022)
    try:
        write_json(tmp_path / "a.json", {"x": 1.0})
        os.umask(0o077)
        with atomic_path(tmp_path / "b.txt") as tmp:
            tmp.write_text("b\n")
        with pytest.raises(RuntimeError), atomic_path(tmp_path / "c.txt") as tmp:
            tmp.write_text("partial\n")
            raise RuntimeError("killed")
    finally:
        os.umask(old)
    assert stat.S_IMODE((tmp_path / "a.json").stat().st_mode) == 0o644
    assert stat.S_IMODE((tmp_path / "b.txt").stat().st_mode) == 0o600
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.json", "b.txt"]
