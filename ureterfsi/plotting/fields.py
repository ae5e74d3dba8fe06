"""Figures from the run's field files (read by ureterfsi.data.fieldfiles): the flow at a side hole, the pressure
along the segment."""
from __future__ import annotations

import numpy as np
from matplotlib.patches import Rectangle

from ureterfsi.data.fieldfiles import Section
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
