"""Figures from the run's field files (read by ureterfsi.data.fieldfiles): the flow at a side hole, the wall shear
stress on the stent around it, the pressure along the segment."""
from __future__ import annotations

import numpy as np
from matplotlib.colors import LogNorm
from matplotlib.patches import Rectangle

from ureterfsi.data.fieldfiles import Section, StentWallShear
from ureterfsi.plotting.style import plt, styled


@styled
def fig_hole_flow(sec: Section, hole_z: float, geom, title: str):
    """The Section of hole_flow_section: urine speed |v| (colour, one scale for every instant) and streamlines
    of the in-plane velocity (v_y, v_z); the stent wall (grey) with the hole, and the ureter inner wall at rest
    (dashed) outlined."""
    fig, axes = plt.subplots(1, len(sec.times), figsize=(3.2 * len(sec.times) + 1.0, 4.2), sharey=True,
                             constrained_layout=True)
    axes = np.atleast_1d(axes)
    vmax = max(float(np.nanmax(np.linalg.norm(v, axis=2))) for v in sec.values) * 1e3
    zmm, ymm = sec.z * 1e3, sec.y * 1e3
    ri, ro, rh = geom.stent_inner_radius * 1e3, geom.stent_outer_radius * 1e3, geom.hole_radius * 1e3
    zl, zh = zmm[0], zmm[-1]
    for ax, t, v in zip(axes, sec.times, sec.values):
        speed = np.linalg.norm(v, axis=2) * 1e3
        im = ax.pcolormesh(zmm, ymm, speed, shading="auto", cmap="viridis", vmin=0.0, vmax=vmax)
        vy, vz = np.ma.masked_invalid(v[..., 1]), np.ma.masked_invalid(v[..., 2])
        ax.streamplot(zmm, ymm, vz, vy, color="w", density=1.1, linewidth=0.6, arrowsize=0.7)
        for a, b in ((zl, hole_z * 1e3 - rh), (hole_z * 1e3 + rh, zh)):
            ax.add_patch(Rectangle((a, ri), b - a, ro - ri, facecolor="0.6", edgecolor="k", lw=0.8))
        ax.axhline(geom.ureter_inner_radius * 1e3, color="k", ls="--", lw=0.8)
        ax.set_title(f"t = {t:g} s")
        ax.set_xlabel("z (mm)")
        ax.set_xlim(zl, zh)
        ax.set_ylim(ymm[0], ymm[-1])
        ax.set_facecolor("0.85")
    axes[0].set_ylabel("y (mm), plane x = 0")
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
def fig_stent_wall_shear(ws: StentWallShear, hole_z: float, hole_angles, geom, threshold: float, title: str):
    """The StentWallShear unrolled onto (angle, z), one column per instant: the outer surface with the holes'
    channels (top row) and the lumen (bottom row); log colour scale, the low-WSS threshold marked on the colour
    bar; the outlines of the holes at `hole_angles` (deg; r_h / r_o wide in angle) dashed."""
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
            for axis_angle in hole_angles:
                half = np.degrees(geom.hole_radius / geom.stent_outer_radius)
                ax.add_patch(Rectangle((axis_angle - half, hole_z * 1e3 - geom.hole_radius * 1e3), 2 * half,
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
