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
    for name, fig in (("flow", fig_hole_flow(sec, [zh], g, "test")),
                      ("pressure", fig_pressure_along(lines, times, p_ref, centres, "test"))):
        png = tmp_path / f"{name}.png"
        save_figure(fig, [png], dpi=60)
        assert png.stat().st_size > 10_000


def _geometry(**geometry):
    from ureterfsi.mesh.geometry import UreterGeometry

    cfg = load_config_files([REPO / "config" / "config.yaml"])
    cfg["geometry"].update(geometry)
    return UreterGeometry.from_config(cfg)


def test_the_field_window_holds_the_obstruction_and_its_nearest_holes():
    """field_window: around an occlusion (or a stricture) from 1 mm before the nearest hole upstream to 1 mm past
    the nearest one downstream, every hole in it listed; without one, the outlet-most hole +- 2 mm; clipped to the
    segment; an obstruction with no hole on a side keeps +- 2 mm on that side."""
    from ureterfsi.plotting.fields import field_window

    holes = np.array([1.25e-3, 1.25e-3, 10e-3, 10e-3, 20e-3, 20e-3, 48.75e-3, 48.75e-3])
    w = field_window(holes, _geometry(occlusion_length=1e-3, occlusion_position=0.015, occlusion_taper=1.5e-3))
    assert (w.lo, w.hi) == pytest.approx((9e-3, 21e-3)) and w.holes == (2, 3, 4, 5)
    assert "occlusion at z = 15 mm" in w.label and "10, 20 mm" in w.label
    w = field_window(holes, _geometry(stricture_fraction=0.7, stricture_length=4e-3, stricture_position=0.005))
    assert (w.lo, w.hi) == pytest.approx((0.25e-3, 11e-3)) and w.holes == (0, 1, 2, 3) and "stricture" in w.label
    w = field_window(holes[:2], _geometry(occlusion_length=1e-3, occlusion_position=0.03, occlusion_taper=1.5e-3))
    assert (w.lo, w.hi) == pytest.approx((0.25e-3, 32e-3)) and w.holes == (0, 1)
    w = field_window(holes, _geometry())
    assert (w.lo, w.hi) == pytest.approx((46.75e-3, 50e-3)) and w.holes == (6, 7) and "outlet-most" in w.label
    assert w.centre == pytest.approx(48.375e-3) and w.half_width == pytest.approx(1.625e-3)


def test_field_figures_around_an_occlusion_draw_every_hole_of_the_window(tmp_path):
    """The flow figure over a long window (stacked instants) cuts the stent wall at each in-plane hole and follows
    the occluded wall; the WSS figure outlines each hole of the window; both are drawn and saved."""
    from ureterfsi.data.fieldfiles import Section, StentWallShear
    from ureterfsi.plotting.fields import fig_hole_flow, fig_stent_wall_shear, field_window
    from ureterfsi.plotting.style import save_figure

    g = _geometry(occlusion_length=1e-3, occlusion_position=0.015, occlusion_taper=1.5e-3)
    w = field_window(np.array([10e-3, 20e-3]), g)
    y, z = np.linspace(0.0, g.ureter_inner_radius, 30), np.linspace(w.lo, w.hi, 240)
    v = np.zeros((y.size, z.size, 3))
    v[..., 2] = 1e-3 * (1.0 - (y[:, None] / g.ureter_inner_radius) ** 2)
    fig = fig_hole_flow(Section(y, z, [0.5, 1.0], [v, 2 * v]), [10e-3, 20e-3], g, "test")
    from matplotlib.patches import Rectangle

    axes = fig.axes[:2]
    walls = [[p for p in ax.patches if isinstance(p, Rectangle)] for ax in axes]
    assert [len(w_) for w_ in walls] == [3, 3]                  # wall pieces before, between and after the holes
    edges = sorted(e for p in walls[0] for e in (p.get_x(), p.get_x() + p.get_width()))
    rh = g.hole_radius * 1e3
    assert edges[1:5] == pytest.approx([10 - rh, 10 + rh, 20 - rh, 20 + rh])
    wall = axes[0].lines[-1].get_ydata()
    assert wall.min() == pytest.approx(g.stent_outer_radius * 1e3, rel=1e-6)   # the wall on the stent
    rng = np.random.default_rng(0)
    n = 500
    ws = StentWallShear(rng.uniform(-np.pi, np.pi, n), rng.uniform(w.lo, w.hi, n),
                        np.full(n, g.stent_outer_radius), [0.5], [rng.uniform(1e-3, 1.0, n)])
    fig2 = fig_stent_wall_shear(ws, [(90.0, 10e-3), (90.0, 20e-3)], g, 0.04, "test")
    assert len([p for p in fig2.axes[0].patches if isinstance(p, Rectangle)]) == 2
    for name, f in (("flow", fig), ("wss", fig2)):
        png = tmp_path / f"{name}.png"
        save_figure(f, [png], dpi=60)
        assert png.stat().st_size > 10_000
