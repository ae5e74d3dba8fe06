"""The stability map: every case of the stability matrix (ureterfsi.stability) along its axis, its outcome
(stable, or the limit that ended it) and how far it came."""
from __future__ import annotations

import matplotlib
import matplotlib.pyplot as plt
import numpy as np
import xarray as xr

from ureterfsi.plotting.paper import KPA, MM, MM_S
from ureterfsi.plotting.style import styled
from ureterfsi.stability import AXES, AXIS_PARAMETER, format_value

# marker of each outcome / limit of ureterfsi.stability
STABILITY_MARKERS = {"stable": ("o", "stable"), "ale_inversion": ("^", "failed: ALE inversion"),
                     "newton": ("s", "failed: Newton (after halvings)"), "nan": ("X", "failed: NaN"),
                     "energy": ("D", "failed: energy bound"), "volume": ("v", "failed: volume balance"),
                     "wall_time": ("P", "failed: wall-time budget"), "exception": ("*", "failed: error")}
STABILITY_SHORT = {"ale_inversion": "ALE", "newton": "Newton", "nan": "NaN", "energy": "energy",
                   "volume": "volume", "wall_time": "budget", "exception": "error"}
# display scale of each axis's parameter: (factor, unit label)
STABILITY_UNITS = {"time_step": (1.0, "s"), "mesh_level": (1.0, "cells"), "bulk_ratio": (1.0, ""),
                   "density_ratio": (1.0, ""), "load_amplitude": (KPA, "kPa"), "wave_speed": (MM_S, "mm/s"),
                   "wave_width": (MM, "mm"), "viscosity": (1e3, "mPa s"), "hole_elements": (1.0, "")}


@styled
def stability_map(ds: xr.Dataset):
    """Stability matrix (ureterfsi.stability.combine): one panel row per varied quantity.

    Left: volume balance error vs the parameter (log x where the values span decades), marker = outcome
    (failed cases by the limit they hit, labelled with it and the time), colour = minimum ALE Jacobian,
    ring = baseline of the row's scene (r-z: the baseline case; 3D hole rows: the case on the study's own
    mesh), dashed line = stability.volume_tolerance. Right: kinetic energy vs time of the same cases
    (colour = parameter, black = baseline; a cross where a failed case stopped)."""
    axes_present = [a for a in AXES if a in set(str(x) for x in ds["axis"].values)]
    n = max(len(axes_present), 1)
    fig, axs = plt.subplots(n, 2, figsize=(10.0, 1.95 * n + 0.9), squeeze=False,
                            gridspec_kw={"width_ratios": [1.15, 1.0]})
    jnorm = matplotlib.colors.Normalize(0.0, 1.0)
    jcmap = plt.get_cmap("RdYlGn")
    tol = float(ds.attrs.get("volume_tolerance", np.nan) or np.nan)
    axis_of = np.array([str(a) for a in ds["axis"].values])
    scene_of = np.array([str(a) for a in ds["scene"].values]) if "scene" in ds else np.full(axis_of.size, "rz")
    is_base = ds["is_baseline"].values.astype(bool) if "is_baseline" in ds else axis_of == "baseline"
    base = np.flatnonzero(axis_of == "baseline")
    for row, name in enumerate(axes_present):
        left, right = axs[row]
        members = np.flatnonzero(axis_of == name)
        # a row of the 3D hole scene has its own baseline among its members
        idx = (members if (scene_of[members] != "rz").any() else np.concatenate([base, members])).astype(int)
        factor, unit = STABILITY_UNITS.get(name, (1.0, AXES[name][0]))
        x = ds[AXIS_PARAMETER[name]].values[idx].astype(float) * factor
        order = np.argsort(x, kind="stable")
        idx, x = idx[order], x[order]
        verr = ds["volume_error"].values[idx].astype(float)
        jmin = ds["min_jacobian"].values[idx].astype(float)
        pos = verr[np.isfinite(verr) & (verr > 0)]
        floor = 0.2 * pos.min() if pos.size else 1e-6   # a case without flow has no error: drawn at the floor
        y = np.where(np.isfinite(verr) & (verr > 0), verr, floor)
        left.plot(x, y, color="0.6", lw=0.8, zorder=1)
        for k, i in enumerate(idx):
            outcome, limit = str(ds["outcome"].values[i]), str(ds["limit"].values[i])
            key = "stable" if outcome == "stable" else limit
            marker = STABILITY_MARKERS.get(key, ("*", key))[0]
            left.scatter([x[k]], [y[k]], marker=marker, s=55, c=[jcmap(jnorm(np.clip(jmin[k], 0, 1)))],
                         edgecolors="k", linewidths=0.7, zorder=3)
            if is_base[i]:
                left.scatter([x[k]], [y[k]], marker="o", s=170, facecolors="none", edgecolors="k",
                             linewidths=0.9, zorder=2)
            label = None
            if name == "mesh_level":
                label = str(ds["mesh_level"].values[i])
            if np.isfinite(verr[k]) and verr[k] == 0.0:
                label = "error 0 (nothing moves)"
            if outcome != "stable":
                ft = float(ds["failure_time"].values[i])
                what = STABILITY_SHORT.get(limit, limit)
                when = f" t={ft:.2g} s" if np.isfinite(ft) else ""
                label = f"{label + ': ' if label else ''}{what}{when}"
            if label:
                right_half = x.size > 1 and k >= x.size / 2
                left.annotate(label, (x[k], y[k]), textcoords="offset points", xytext=(-5 if right_half else 5, 5),
                              ha="right" if right_half else "left", fontsize=7,
                              color="k" if outcome == "stable" else "crimson")
        if np.isfinite(tol):
            left.axhline(tol, color="crimson", lw=0.8, ls="--", zorder=0)
        left.set_yscale("log")
        left.set_ylim(min(y.min(), tol if np.isfinite(tol) else y.min()) / 3.0,
                      max(y.max(), tol if np.isfinite(tol) else y.max()) * 6.0)
        positive = x[x > 0]
        if AXES[name][2] in ("log", "symlog") and positive.size and positive.max() / positive.min() > 3.0:
            if AXES[name][2] == "symlog" and (x <= 0).any():
                left.set_xscale("symlog", linthresh=positive.min(), linscale=0.6)
            else:
                left.set_xscale("log")
        if left.get_xscale() == "symlog":
            left.set_xlim(-0.3 * positive.min(), positive.max() * 1.6)
        elif left.get_xscale() == "linear":
            pad = 0.08 * (x.max() - x.min() if x.size and x.max() > x.min() else 1.0)
            left.set_xlim(x.min() - pad, x.max() + pad)
        else:
            left.set_xlim(positive.min() / 1.6, positive.max() * 1.6)
        # ticks at the values of the cases, in the display unit
        ticks = np.unique(x)
        left.xaxis.set_major_locator(matplotlib.ticker.FixedLocator(ticks))
        left.xaxis.set_minor_locator(matplotlib.ticker.NullLocator())
        labels = [f"{v:.0f}" if name == "mesh_level" else format_value(float(f"{v:.3g}")) for v in ticks]
        left.xaxis.set_major_formatter(matplotlib.ticker.FixedFormatter(labels))
        left.tick_params(axis="x", labelsize=7)
        left.set_xlabel(f"{AXES[name][1]}" + (f" ({unit})" if unit else ""))
        left.set_ylabel("volume balance\nerror (rel.)")
        # right: kinetic energy histories
        pnorm = (matplotlib.colors.LogNorm(positive.min(), positive.max()) if left.get_xscale() in ("log", "symlog")
                 and positive.size else matplotlib.colors.Normalize(x.min(), x.max() if x.max() > x.min() else x.min() + 1))
        pcmap = plt.get_cmap("viridis")
        for k, i in enumerate(idx):
            t = ds["time"].values[i].astype(float)
            e = ds["kinetic_energy"].values[i].astype(float)
            ok = np.isfinite(t) & np.isfinite(e) & (e > 0)
            if not ok.any():
                continue
            colour = "k" if is_base[i] else pcmap(pnorm(x[k])) if x[k] > 0 or left.get_xscale() == "linear" else "0.5"
            right.plot(t[ok], e[ok], color=colour, lw=1.4 if is_base[i] else 1.0,
                       label=("baseline " if is_base[i] else "") + (
                           f"{x[k]:.0f}" if name == "mesh_level" else format_value(float(f"{x[k]:.3g}"))))
            if str(ds["outcome"].values[i]) != "stable" and str(ds["limit"].values[i]) != "volume":
                right.plot(t[ok][-1], e[ok][-1], marker="x", color="crimson", ms=6, mew=1.5)
        right.set_yscale("log")
        e_all = ds["kinetic_energy"].values[idx].astype(float).ravel()
        e_all = e_all[np.isfinite(e_all) & (e_all > 0)]
        if e_all.size:   # the fluid starts at rest (E = 0 up to round-off): show four decades below the peak
            right.set_ylim(e_all.max() * 1e-4, e_all.max() * 3.0)
        right.set_xlabel("time (s)")
        right.set_ylabel("kinetic\nenergy (J)")
        right.legend(fontsize=6, loc="upper left", bbox_to_anchor=(1.01, 1.0), title_fontsize=6,
                     title=name.replace("_", " ") + (f" ({unit})" if unit else ""))
    handles = [plt.Line2D([], [], ls="none", marker=m, markerfacecolor="0.85", markeredgecolor="k", label=lab)
               for key, (m, lab) in STABILITY_MARKERS.items()
               if key == "stable" or key in set(str(v) for v in ds["limit"].values)]
    handles.append(plt.Line2D([], [], ls="none", marker="o", ms=11, markerfacecolor="none", markeredgecolor="k",
                              label="baseline"))
    handles.append(plt.Line2D([], [], color="crimson", ls="--", lw=0.8, label="volume tolerance"))
    fig.legend(handles=handles, loc="outside lower center", ncols=min(len(handles), 5))
    fig.colorbar(matplotlib.cm.ScalarMappable(norm=jnorm, cmap=jcmap), ax=list(axs[:, 0]), location="left",
                 label="minimum ALE Jacobian (over the run)", shrink=0.4, pad=0.02)
    stable = int(np.sum(ds["outcome"].values.astype(str) == "stable"))
    scenes = "r-z, fully coupled" + ("; side holes: 3D, one-way" if (scene_of == "holes").any() else "")
    fig.suptitle(f"Stability matrix ({scenes}): {stable} of {ds.sizes['case']} cases stable\n"
                 f"one-at-a-time variations around the baseline")
    return fig
