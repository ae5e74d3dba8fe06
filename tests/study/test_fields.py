"""Field files (ureterfsi.study.fields): a one-way run of the 10 mm segment (model 3, two 20 ms steps) writes XDMF
snapshots at its probe times; read back without dolfinx, they match the run's own diagnostics exactly."""
from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

from ureterfsi.config import load_config_files

REPO = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="module")
def run(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("fields")
    cfg = load_config_files([REPO / "config" / "config.yaml", REPO / "config" / "segment-10mm.yaml"])
    cfg["time"].update(end=0.04, dt=0.02, probe_times=[0.02, 0.04])
    cfg["peristalsis"]["ramp_time"] = 0.039
    cfg["figures"].update(wave_times=[0.02, 0.04], hole_velocity_times=[0.02, 0.04, 0.02, 0.04])
    (tmp / "cfg.json").write_text(json.dumps(cfg, default=float))
    from ureterfsi.mesh.build import build_mesh

    build_mesh(cfg, "3", "coarse", "quarter", tmp / "m3.msh", tmp / "m3.json")
    out = tmp / "runs" / "one_way" / "quarter" / "model3_coarse.nc"
    subprocess.run([sys.executable, "-m", "ureterfsi.study", "--config-json", str(tmp / "cfg.json"), "--model", "3",
                    "--level", "coarse", "--symmetry", "quarter", "--mesh", str(tmp / "m3.msh"), "--out", str(out),
                    "--fidelity", "one_way"], check=True, cwd=REPO, capture_output=True)
    with xr.open_dataset(out, decode_times=False) as ds:
        ds.load()
    return ds, out, cfg


def test_field_files_referenced_from_dataset(run):
    ds, out, _ = run
    d = (out.parent / ds.attrs["fields_path"]).resolve()
    assert d == (out.parent.parent.parent.parent / "fields" / "one_way" / "quarter" / "model3_coarse").resolve()
    manifest = json.loads((d / "fields.json").read_text())
    assert manifest["times"] == [0.02, 0.04] and set(manifest["parts"]) == {"urine", "stent"}
    assert ds.attrs["fields_size_bytes"] == sum(f.stat().st_size for f in d.iterdir() if f.name != "fields.json")
    assert not list(d.parent.glob("*.part"))          # staging directory renamed into place
    assert 0 < ds.attrs["fields_write_time_s"] < 0.05 * ds.attrs["wall_time_s"]


def test_wall_pressure_matches_run_diagnostic(run):
    """max over snapshots and wall vertices of |p - p_ref| = the run's one_way_max_wall_pressure_deviation
    (both: P1 pressure dofs on the fluid-ureter interface, every step of this run is a snapshot)."""
    from ureterfsi.data.fieldfiles import read_fields

    ds, out, cfg = run
    fs = read_fields(out.parent / ds.attrs["fields_path"], "urine")
    R = np.hypot(fs.points[:, 0], fs.points[:, 1])
    wall = np.abs(R - cfg["geometry"]["ureter_outer_diameter"] / 2 + cfg["geometry"]["ureter_wall_thickness"]) < 1e-7
    assert wall.sum() > 100
    dev = max(np.abs(fs.values("pressure", t)[wall, 0] - cfg["fluid"]["reference_pressure"]).max() for t in fs.times)
    assert dev == pytest.approx(ds.attrs["one_way_max_wall_pressure_deviation"], rel=1e-12)
    assert fs.units["pressure"] == "Pa"


def test_stent_von_mises_cell_means_bounded_by_run_maximum(run):
    """DG0 cell means of the stent stress never exceed the run's maximum of the DG1 field, and reach most of it."""
    from ureterfsi.data.fieldfiles import read_fields

    ds, out, _ = run
    fs = read_fields(out.parent / ds.attrs["fields_path"], "stent")
    for t, vmax in zip(ds["time"].values[1:], ds["stent_max_von_mises"].values[1:]):
        vm = fs.values("von_mises", float(t))[:, 0]
        assert vm.size == len(fs.cells) and vm.max() <= vmax * (1 + 1e-12) and vm.max() > 0.5 * vmax


def test_hole_velocity_of_the_figure_matches_run_probe(run):
    """The figure's section (hole_flow_section: urine cells, current configuration) on the run's probe line
    across the outlet-most hole (x = 0, r = probe radius) against the run's hole_velocity_y (the P2 field at
    the probe points): the field file holds the P1 vertex values, so they agree to the P1 interpolation error
    of the hole's few elements, < 10 % of the peak (a wrong time, component, sign or hole is off by ~100 %)."""
    from ureterfsi.mesh.geometry import UreterGeometry
    from ureterfsi.data.fieldfiles import hole_flow_section, urine_fields

    ds, out, cfg = run
    g = UreterGeometry.from_config(cfg)
    fs = urine_fields(out.parent / ds.attrs["fields_path"])
    zh, s = float(ds["hole_z"].max()), ds["hole_offset"].values
    times = [float(t) for t in ds["probe_time"].values]
    sec = hole_flow_section(fs, times, zh, g, y=[g.probe_radius], z=zh + s)
    probe = ds["hole_velocity_y"].values
    field = np.array([v[0, :, 1] for v in sec.values])
    both = np.isfinite(probe) & np.isfinite(field)
    assert both.sum() >= 0.8 * probe.size
    peak = np.abs(probe[both]).max()
    err = np.abs(field - probe)[both].max() / peak
    print(f"hole velocity, field file vs probe: max difference {err:.3f} of the peak {peak:.3e} m/s")
    assert peak > 0 and err < 0.1


def test_field_figures_from_the_field_file(run, tmp_path):
    """Both field figures are drawn from the run's field file: the section is NaN in the stent wall and
    finite in the hole channel and the lumen; the wall pressure line stays within the run's maximum wall
    pressure deviation (a line through the P1 values of the wall vertices) and reaches most of it."""
    from ureterfsi.mesh.geometry import UreterGeometry
    from ureterfsi.data.fieldfiles import hole_flow_section, pressure_lines, urine_fields
    from ureterfsi.plotting.fields import fig_hole_flow, fig_pressure_along
    from ureterfsi.plotting.style import save_figure

    ds, out, cfg = run
    g = UreterGeometry.from_config(cfg)
    fs = urine_fields(out.parent / ds.attrs["fields_path"])
    times = [float(t) for t in ds["probe_time"].values]
    zh = float(ds["hole_z"].max())
    sec = hole_flow_section(fs, times, zh, g)
    Y, Z = np.meshgrid(sec.y, sec.z, indexing="ij")
    in_stent = (Y > g.stent_inner_radius * 1.05) & (Y < g.stent_outer_radius * 0.95)
    wall = in_stent & (np.abs(Z - zh) > 1.5 * g.hole_radius)
    channel = in_stent & (np.abs(Z - zh) < 0.5 * g.hole_radius)
    lumen = Y < 0.8 * g.stent_inner_radius
    for v in sec.values:
        speed = np.linalg.norm(v, axis=2)
        assert wall.any() and np.isnan(speed[wall]).all()
        assert channel.any() and np.isfinite(speed[channel]).all() and np.isfinite(speed[lumen]).all()
    p_ref = cfg["fluid"]["reference_pressure"]
    lines = pressure_lines(fs, times, g)
    p_wall = lines["ureter inner wall"][1]
    dev, run_dev = np.nanmax(np.abs(p_wall - p_ref)), ds.attrs["one_way_max_wall_pressure_deviation"]
    assert np.isfinite(p_wall).all() and np.isfinite(lines["stent lumen (r = r_i / 2)"][1]).all()
    assert 0.5 * run_dev < dev <= run_dev * (1 + 1e-6)
    centres = [float(ds["pulse_centre"].sel(time=t, method="nearest")) for t in times]
    for name, fig in (("flow", fig_hole_flow(sec, zh, g, "test")),
                      ("pressure", fig_pressure_along(lines, times, p_ref, centres, "test"))):
        png = tmp_path / f"{name}.png"
        save_figure(fig, [png], dpi=60)
        assert png.stat().st_size > 10_000
