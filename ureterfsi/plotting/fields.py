"""Figures from the run's field files (read by ureterfsi.data.fieldfiles; run_field_figure: one of a run file): the
flow through the side holes of a window of the segment, the wall shear stress on the stent there, the pressure along
the segment. The window (field_window) holds the obstruction and the nearest hole on each side of it, or the
outlet-most side hole."""
from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from matplotlib.colors import LogNorm
from matplotlib.patches import Rectangle

from ureterfsi.data import fieldfiles
from ureterfsi.data.checked import RUN_FILE, open_netcdf
from ureterfsi.data.fieldfiles import Section, StentWallShear
from ureterfsi.mesh.geometry import UreterGeometry
from ureterfsi.plotting.style import plt, styled


@dataclass(frozen=True)
class FieldWindow:
    """The axial window lo <= z <= hi (m) a field figure shows, the side holes in it (indices into the run's hole
    arrays) and the words of the figure's title."""
    lo: float
    hi: float
    holes: tuple
    label: str

    @property
    def centre(self) -> float:
        return 0.5 * (self.lo + self.hi)

    @property
    def half_width(self) -> float:
        return 0.5 * (self.hi - self.lo)


def field_window(hole_z, geom, margin: float = 1.0e-3, half_width: float = 2.0e-3) -> FieldWindow:
    """Around the obstruction (geom.obstruction_centre z_c): from the nearest hole upstream of z_c less `margin` to
    the nearest hole downstream plus `margin` (z_c -+ half_width on a side without a hole), where urine enters and
    leaves the stent past it; without an obstruction, the outlet-most side hole +- half_width (Figs. 6-9).
    Clipped to the segment."""
    hole_z = np.asarray(hole_z, dtype=float)
    zc = geom.obstruction_centre
    if zc is None:
        zh = float(hole_z.max())
        lo, hi = zh - half_width, zh + half_width
        label = f"around the outlet-most side hole (z = {zh * 1e3:g} mm)"
    else:
        up, down = hole_z[hole_z < zc], hole_z[hole_z > zc]
        lo = float(up.max()) - margin if up.size else zc - half_width
        hi = float(down.min()) + margin if down.size else zc + half_width
        label = f"around the {geom.obstruction} at z = {zc * 1e3:g} mm"
    lo, hi = max(lo, 0.0), min(hi, geom.length)
    holes = tuple(int(k) for k in np.flatnonzero((hole_z >= lo) & (hole_z <= hi)))
    shown = sorted({round(float(hole_z[k]) * 1e3, 6) for k in holes})
    if zc is not None:
        label += f" (side holes at {', '.join(f'{z:g}' for z in shown)} mm)" if shown else " (no side hole near it)"
    return FieldWindow(lo, hi, holes, label)


@styled
def fig_hole_flow(sec: Section, hole_zs, geom, title: str):
    """The Section of hole_flow_section: urine speed |v| (colour, one scale for every instant) and streamlines
    of the in-plane velocity (v_y, v_z); the stent wall (grey) cut by the plane's side holes at `hole_zs` (m), and
    the ureter's inner wall at rest (dashed; narrowed by a stricture or an occlusion) outlined. A window longer than
    6 mm stacks the instants."""
    zmm, ymm = sec.z * 1e3, sec.y * 1e3
    zl, zh = zmm[0], zmm[-1]
    wide = zh - zl > 6.0
    n = len(sec.times)
    fig, axes = plt.subplots(n if wide else 1, 1 if wide else n, sharex=wide, sharey=True, constrained_layout=True,
                             figsize=(10.0, 1.7 * n + 1.0) if wide else (3.2 * n + 1.0, 4.2))
    axes = np.atleast_1d(axes)
    vmax = max(float(np.nanmax(np.linalg.norm(v, axis=2))) for v in sec.values) * 1e3
    ri, ro, rh = geom.stent_inner_radius * 1e3, geom.stent_outer_radius * 1e3, geom.hole_radius * 1e3
    edges = [zl, *[e for z in sorted(np.asarray(hole_zs, float) * 1e3) for e in (z - rh, z + rh)], zh]
    wall_z = np.linspace(zl, zh, 400)
    for ax, t, v in zip(axes, sec.times, sec.values):
        speed = np.linalg.norm(v, axis=2) * 1e3
        im = ax.pcolormesh(zmm, ymm, speed, shading="auto", cmap="viridis", vmin=0.0, vmax=vmax)
        vy, vz = np.ma.masked_invalid(v[..., 1]), np.ma.masked_invalid(v[..., 2])
        ax.streamplot(zmm, ymm, vz, vy, color="w", density=1.1, linewidth=0.6, arrowsize=0.7)
        for a, b in zip(edges[::2], edges[1::2]):
            if b > a:
                ax.add_patch(Rectangle((a, ri), b - a, ro - ri, facecolor="0.6", edgecolor="k", lw=0.8))
        ax.plot(wall_z, geom.inner_radius(wall_z * 1e-3) * 1e3, color="k", ls="--", lw=0.8)
        ax.set_title(f"t = {t:g} s")
        ax.set_xlim(zl, zh)
        ax.set_ylim(ymm[0], ymm[-1])
        ax.set_facecolor("0.85")
        if not wide:
            ax.set_xlabel("z (mm)")
    axes[-1].set_xlabel("z (mm)")
    for ax in axes if wide else axes[:1]:
        ax.set_ylabel("y (mm), plane x = 0")
    fig.colorbar(im, ax=axes, label="urine speed |v| (mm s$^{-1}$)")
    fig.suptitle(title)
    return fig


@styled
def fig_pressure_along(lines: dict, times, p_ref: float, pulse_centres, title: str):
    """The lines of pressure_lines, p - p_ref, one panel per line and one curve per time; the pulse centre
    at each time marked (dotted)."""
    fig, axes = plt.subplots(len(lines), 1, figsize=(7.0, 5.5), sharex=True, constrained_layout=True)
    for ax, (label, (z, p)) in zip(axes, lines.items()):
        for k, t in enumerate(times):
            (line,) = ax.plot(z * 1e3, p[k] - p_ref, label=f"t = {t:g} s")
            ax.axvline(pulse_centres[k] * 1e3, color=line.get_color(), ls=":", lw=0.8)
        ax.set_ylabel(f"p - p_ref (Pa)\n{label}")
        ax.grid(alpha=0.3)
    axes[0].legend(fontsize=8)
    axes[-1].set_xlabel("z (mm), inlet (kidney) 0 to outlet (bladder)")
    axes[-1].set_xlim(0.0, z[-1] * 1e3)
    fig.suptitle(title)
    return fig


def hole_angle(axis: int, side: float) -> float:
    """Angle (deg) around the stent axis of a hole on axis 0 = x / 1 = y, side +-1."""
    return 90.0 * side if axis == 1 else (0.0 if side > 0 else 180.0)


@styled
def fig_stent_wall_shear(ws: StentWallShear, holes, geom, threshold: float, title: str):
    """The StentWallShear unrolled onto (angle, z), one column per instant: the outer surface with the holes'
    channels (top row) and the lumen (bottom row); log colour scale, the low-WSS threshold marked on the colour
    bar; the outlines of the `holes`, (angle (deg), z (m)) pairs, r_h / r_o wide in angle, dashed."""
    rows = {"outer surface and hole walls": ws.radius > geom.stent_inner_radius,
            "lumen": ws.radius <= geom.stent_inner_radius}
    fig, axes = plt.subplots(2, len(ws.times), figsize=(3.0 * len(ws.times) + 1.2, 5.6), sharex=True, sharey=True,
                             constrained_layout=True, squeeze=False)
    finite = np.concatenate([v[v > 0] for v in ws.values])
    norm = LogNorm(vmin=max(float(finite.min()), 1e-4 * float(finite.max())), vmax=float(finite.max()))
    deg, zmm = np.degrees(ws.theta), ws.z * 1e3
    for j, (t, v) in enumerate(zip(ws.times, ws.values)):
        for i, (label, sel) in enumerate(rows.items()):
            ax = axes[i, j]
            sc = ax.scatter(deg[sel], zmm[sel], c=np.maximum(v[sel], norm.vmin), s=6, cmap="viridis", norm=norm,
                            linewidths=0)
            for axis_angle, hz in holes:
                half = np.degrees(geom.hole_radius / geom.stent_outer_radius)
                ax.add_patch(Rectangle((axis_angle - half, hz * 1e3 - geom.hole_radius * 1e3), 2 * half,
                                       2 * geom.hole_radius * 1e3, fill=False, ls="--", lw=0.8, ec="k"))
            ax.set_title(f"t = {t:g} s" if i == 0 else "")
            if j == 0:
                ax.set_ylabel(f"z (mm)\n{label}")
            if i == 1:
                ax.set_xlabel("angle around the stent axis (deg)")
    cb = fig.colorbar(sc, ax=axes, label="wall shear stress (Pa)")
    cb.ax.axhline(threshold, color="r", lw=1.5)
    fig.suptitle(title)
    return fig


FIELD_FIGURES = ("field_hole_flow", "field_stent_wss", "field_pressure")


def run_field_figure(kind: str, run_path, cfg: dict, times, what: str):
    """Figure `kind` (FIELD_FIGURES) of the run file `run_path` from its field files (its attribute fields_path),
    at the snapshot `times` (s; None: every snapshot); the geometry and p_ref from `cfg`, the run's configuration;
    `what` names the run in the title."""
    run = open_netcdf(run_path, RUN_FILE)
    # the field directory as a clean path (messages name its files): fields_path is relative to the run file
    fs = fieldfiles.urine_fields(Path(os.path.normpath(Path(run_path).parent / run.attrs["fields_path"])))
    times = [float(t) for t in (fs.times if times is None else times)]
    geom = UreterGeometry.from_config(cfg)
    if kind == "field_pressure":
        lines = fieldfiles.pressure_lines(fs, times, geom)
        centres = [float(run["pulse_centre"].sel(time=t, method="nearest")) for t in times]
        return fig_pressure_along(lines, times, float(cfg["fluid"]["reference_pressure"]), centres,
                                  f"Urine pressure along the segment\n{what}")
    win = field_window(run["hole_z"].values, geom)
    if kind == "field_hole_flow":
        z = np.linspace(win.lo, win.hi, max(120, int(round((win.hi - win.lo) / 5.0e-5)) + 1))
        sec = fieldfiles.hole_flow_section(fs, times, win.centre, geom, z=z)
        in_plane = [float(run["hole_z"].values[k]) for k in win.holes if int(run["hole_axis"].values[k]) == 1]
        return fig_hole_flow(sec, in_plane, geom, f"Urine flow {win.label}\n{what}")
    if kind == "field_stent_wss":
        ws = fieldfiles.stent_wall_shear(fs, times, win.centre, geom, half_width=win.half_width)
        holes = [(hole_angle(int(run["hole_axis"].values[k]), float(run["hole_side"].values[k])),
                  float(run["hole_z"].values[k])) for k in win.holes]
        return fig_stent_wall_shear(ws, holes, geom, float(run["low_wss_threshold"]),
                                    f"Wall shear stress on the stent {win.label}\n{what}")
    raise ValueError(f"field figure kind must be one of {FIELD_FIGURES}, got {kind!r}")
