"""Figures of the paper (Figs. 2-10), Table 1, and the side-hole flux figure, from the study datasets.

One function per figure; each returns a matplotlib Figure (Agg backend) in readable scaled units
(mm, kPa, mm/s, mm^3/s). Models are named as in Table 1 through the `model_label` coordinate.
Saved by ureterfsi.plotting.style.save_figure.
"""
from __future__ import annotations

import matplotlib
import matplotlib.pyplot as plt
import numpy as np
import xarray as xr
from matplotlib.collections import PolyCollection
from matplotlib.patches import Patch

from ureterfsi.data.checked import Contract, read_json
from ureterfsi.data.tables import write_table
from ureterfsi.mesh import tags
from ureterfsi.mesh.io import read_msh
from ureterfsi.plotting.style import styled

# paper §3.4: the instants of Fig. 5 (the workflow passes figures.wave_times): the pulse at the top, middle, bottom
# of the segment and at/past the outlet
WAVE_TIMES = (0.5, 1.0, 2.0, 2.5)
MODEL_COLORS = {"1": "0.2", "2": "tab:blue", "3": "tab:orange", "4": "tab:green"}
MODEL_STYLES = {"1": "-", "2": "-", "3": "--", "4": "-."}
REGION_COLORS = {tags.FLUID: "#9ecae1", tags.URETER: "#fdae6b", tags.STENT: "#a1d99b"}
MM, KPA, MM_S, MM3_S = 1e3, 1e-3, 1e3, 1e9


def _models(ds: xr.Dataset, stented_only: bool = False, var: str | None = None):
    """(model, label) of the models to draw; stented_only keeps models with data in `var`."""
    out = []
    for m, lab in zip(ds["model"].values, ds["model_label"].values):
        m = str(m)
        if stented_only and (var not in ds or not np.isfinite(ds[var].sel(model=m).values).any()):
            continue
        out.append((m, str(lab)))
    return out


def _style(m: str) -> dict:
    return {"color": MODEL_COLORS.get(m), "ls": MODEL_STYLES.get(m, "-"), "lw": 1.4}


def _probe_index(ds: xr.Dataset, t: float) -> int | None:
    pt = ds["probe_time"].values.astype(float)
    if not pt.size:
        return None
    i = int(np.argmin(np.abs(pt - t)))
    return i if abs(pt[i] - t) < 1e-6 else None


# ---------------------------------------------------------------------------------------------- Fig. 2
def _facet_regions(cells: dict, facets: np.ndarray) -> np.ndarray:
    """Cell tag of the tetrahedron adjacent to each boundary triangle."""
    keys, owner = [], []
    for tag, tets in cells.items():
        for drop in range(4):
            f = np.sort(np.delete(tets, drop, axis=1), axis=1)
            keys.append(f)
            owner.append(np.full(len(f), tag))
    keys, owner = np.vstack(keys), np.concatenate(owner)
    fk = np.sort(facets, axis=1)
    dt = np.dtype((np.void, keys.dtype.itemsize * 3))
    kv = np.ascontiguousarray(keys).view(dt).ravel()
    fv = np.ascontiguousarray(fk).view(dt).ravel()
    order = np.argsort(kv)
    pos = np.searchsorted(kv[order], fv)
    pos = np.clip(pos, 0, len(kv) - 1)
    found = kv[order][pos] == fv
    out = np.where(found, owner[order][pos], 0)
    return out


def _slice_tets(coords, cells):
    """Polygons (in (z, y)) of the section of the tetrahedra by the plane x = 0, and their cell tags."""
    edges = [(0, 1), (0, 2), (0, 3), (1, 2), (1, 3), (2, 3)]
    polys, regs = [], []
    for tag, tets in cells.items():
        x = coords[tets][:, :, 0]
        cut = tets[(x.min(axis=1) < 0) & (x.max(axis=1) > 0)]
        p = coords[cut]
        for k in range(len(cut)):
            pts = []
            for a, b in edges:
                xa, xb = p[k, a, 0], p[k, b, 0]
                if (xa < 0) != (xb < 0):
                    s = xa / (xa - xb)
                    q = p[k, a] + s * (p[k, b] - p[k, a])
                    pts.append((q[2], q[1]))
            pts = np.array(pts)
            c = pts.mean(axis=0)
            pts = pts[np.argsort(np.arctan2(pts[:, 1] - c[1], pts[:, 0] - c[0]))]
            polys.append(pts)
            regs.append(tag)
    return polys, np.array(regs)


@styled
def fig02_domain(msh_path, hole_z: float | None = None, title: str | None = None):
    """Computational domain of model 3: mesh in the mirror plane x = 0 coloured by region, with a zoom
    on the outlet-most side hole (cut through its axis). Full models: section of the tetrahedra by x = 0;
    r-z meshes: the triangles themselves."""
    msh = read_msh(msh_path)
    coords, cells, dim = msh.coords, msh.cells(), msh.dim
    sym = msh.elements(2, tags.SYMMETRY_X) if dim == 3 and (2, tags.SYMMETRY_X) in msh.groups else None
    if dim == 2:   # r-z section: r = x, z = y
        polys = [coords[c][:, [1, 0]] for c in np.vstack(list(cells.values()))]
        regs = np.concatenate([np.full(len(c), t) for t, c in cells.items()])
        view = "r-z section (axisymmetric mesh)"
    elif sym is not None and len(sym):
        regs = _facet_regions(cells, sym)
        polys = list(coords[sym][:, :, [2, 1]])
        view = "mirror plane x = 0 (mesh facets)"
    else:
        polys, regs = _slice_tets(coords, cells)
        view = "section x = 0 of the tetrahedra (full model)"
    polys = [np.asarray(p) * MM for p in polys]
    colors = [REGION_COLORS.get(int(r), "white") for r in regs]

    fig = plt.figure(figsize=(7.0, 4.2))
    gs = fig.add_gridspec(2, 1, height_ratios=[1.0, 2.2])
    ax, axz = fig.add_subplot(gs[0]), fig.add_subplot(gs[1])
    for a, lw in ((ax, 0.05), (axz, 0.3)):
        a.add_collection(PolyCollection(polys, facecolors=colors, edgecolors="0.25", linewidths=lw))
        a.set_aspect("equal")
        a.grid(False)
    allp = np.vstack(polys)
    ax.set_xlim(allp[:, 0].min(), allp[:, 0].max())
    ax.set_ylim(allp[:, 1].min(), allp[:, 1].max())
    ax.set_xlabel("z (mm)")
    ax.set_ylabel("y (mm)" if dim == 3 else "r (mm)")
    ax.set_title(title or f"Computational domain, {view}")
    if hole_z is None:
        hole_z = allp[:, 0].max() * 0.975 / MM
    zc = hole_z * MM
    ymax = allp[:, 1].max()
    y0 = 0.0 if allp[:, 1].min() >= -1e-9 else -1.5
    axz.set_xlim(zc - 2.5, min(zc + 2.5, allp[:, 0].max()))
    axz.set_ylim(y0, 2.5 if ymax > 2.5 else ymax)
    axz.set_xlabel("z (mm)")
    axz.set_ylabel("y (mm)" if dim == 3 else "r (mm)")
    axz.set_title(f"zoom: outlet-most side hole (z = {zc:.2f} mm)")
    ax.indicate_inset_zoom(axz, edgecolor="k")
    handles = [Patch(facecolor=REGION_COLORS[t], edgecolor="0.25", label=tags.CELL_NAMES[t].capitalize()
                     if t != tags.FLUID else "Urine") for t in (tags.FLUID, tags.URETER, tags.STENT)
               if t in cells]
    axz.legend(handles=handles, loc="upper left", framealpha=0.9)
    return fig


# ---------------------------------------------------------------------------------------------- Fig. 3
@styled
def fig03_mesh_convergence(conv: xr.Dataset):
    """Stent von Mises stress along the probe line at the convergence time, one line per mesh level."""
    fig, ax = plt.subplots(figsize=(6.0, 3.6))
    styles = ["-", "--", "-.", ":"]
    for i, lv in enumerate(conv["level"].values):
        d = conv.sel(level=lv)
        cells = d["cells"].item()
        lab = f"{lv} ({int(cells):,} elements)".replace(",", " ") if np.isfinite(cells) else str(lv)
        ax.plot(conv["z"] * MM, d["stent_von_mises_line"] * KPA, ls=styles[i % 4], lw=1.4, label=lab)
    t = conv.attrs.get("probe_time")
    ax.set_xlabel("z along the stent (mm)")
    ax.set_ylabel("von Mises stress (kPa)")
    ax.set_title(f"Mesh convergence, model {conv.attrs.get('model', '?')}, "
                 f"probe line r = 0.75 mm" + (f", t = {float(t):g} s" if t is not None else ""))
    ax.legend(title="mesh")
    return fig


# ---------------------------------------------------------------------------------------------- Fig. 4
@styled
def fig04_outlet_flow(ds: xr.Dataset):
    """Mean axial outlet velocity (paper's measure) and outlet volumetric flux vs time, all models."""
    fig, (a1, a2) = plt.subplots(2, 1, figsize=(6.0, 5.0), sharex=True)
    for m, lab in _models(ds):
        d = ds.sel(model=m)
        a1.plot(ds["time"], d["outlet_mean_axial_velocity"] * MM_S, label=lab, **_style(m))
        a2.plot(ds["time"], d["outlet_flux"] * MM3_S, label=lab, **_style(m))
    for a in (a1, a2):
        a.axhline(0.0, color="k", lw=0.6)
    a1.set_ylabel("mean axial outlet\nvelocity (mm/s)")
    a2.set_ylabel("outlet flow rate (mm³/s)")
    a2.set_xlabel("time (s)")
    a1.set_title("Outlet flow rate (positive: out of the ureter, towards the bladder)")
    a1.legend(ncols=4, loc="best")
    return fig


# ---------------------------------------------------------------------------------------------- Fig. 5
@styled
def fig05_wall_displacement(ds: xr.Dataset, times=WAVE_TIMES):
    """Radial displacement of the ureter outer wall vs z at `times` (default: the paper's instants; the
    workflow passes figures.wave_times), all models. Times without a probe snapshot are skipped."""
    times = [t for t in times if _probe_index(ds, t) is not None]
    n = max(len(times), 1)
    rows = 2 if n > 2 else 1
    cols = int(np.ceil(n / rows))
    fig, axes = plt.subplots(rows, cols, figsize=(3.3 * cols, 2.6 * rows + 0.4), sharex=True, sharey=True,
                             squeeze=False)
    for k, t in enumerate(times):
        ax = axes.flat[k]
        i = _probe_index(ds, t)
        for m, lab in _models(ds):
            ax.plot(ds["z"] * MM, ds["wall_radial_displacement"].sel(model=m).isel(probe_time=i) * MM,
                    label=lab, **_style(m))
        if "pulse_centre" in ds:
            zc = ds["pulse_centre"].isel(model=0).interp(time=t).item() * MM
            if np.isfinite(zc):
                ax.axvline(zc, color="crimson", lw=0.8, ls=":")
        ax.set_title(f"t = {t:g} s")
    for ax in axes[-1]:
        ax.set_xlabel("z (mm)")
    for ax in axes[:, 0]:
        ax.set_ylabel("radial wall\ndisplacement (mm)")
    for ax in axes.flat[len(times):]:
        ax.set_visible(False)
    h, lab = axes.flat[0].get_legend_handles_labels()
    h.append(plt.Line2D([], [], color="crimson", lw=0.8, ls=":"))
    lab.append("pulse centre")
    fig.legend(h, lab, loc="outside upper center", ncols=len(lab))
    return fig


# ------------------------------------------------------------------------------------------ Figs. 6-9
@styled
def fig_hole_velocity(ds: xr.Dataset, time: float):
    """Velocity along the hole axis (y) across the outlet-most side hole vs distance from its centre."""
    fig, ax = plt.subplots(figsize=(5.0, 3.4))
    i = _probe_index(ds, time)
    for m, lab in _models(ds, stented_only=True, var="hole_velocity_y"):
        if i is None:
            continue
        ax.plot(ds["hole_offset"] * MM, ds["hole_velocity_y"].sel(model=m).isel(probe_time=i) * MM_S,
                marker="o", ms=2.5, label=lab, **_style(m))
    ax.axhline(0.0, color="k", lw=0.6)
    ax.set_xlabel("axial distance from the hole centre (mm)")
    ax.set_ylabel("y-velocity (mm/s)")
    zh = ds["outlet_hole_z"].values
    zh = zh[np.isfinite(zh)]
    where = f" (z = {zh[0] * MM:.2f} mm)" if zh.size else ""
    ax.set_title(f"y-velocity through the outlet-most side hole{where}, t = {time:g} s")
    ax.legend(title="hole-pair spacing")
    if i is None:
        ax.text(0.5, 0.5, f"no probe at t = {time:g} s", transform=ax.transAxes, ha="center")
    return fig


# --------------------------------------------------------------------------------------------- Fig. 10
@styled
def fig10_stent_von_mises(ds: xr.Dataset):
    """Maximum von Mises stress over the stent volume vs time, stented models."""
    fig, ax = plt.subplots(figsize=(6.0, 3.6))
    for m, lab in _models(ds, stented_only=True, var="stent_max_von_mises"):
        ax.plot(ds["time"], ds["stent_max_von_mises"].sel(model=m) * KPA, label=lab, **_style(m))
    ax.set_xlabel("time (s)")
    ax.set_ylabel("maximum von Mises stress (kPa)")
    ax.set_title("Maximum von Mises stress over the stent")
    ax.legend(title="hole-pair spacing")
    return fig


# ------------------------------------------------------------------------------------- side-hole flux
@styled
def fig_hole_flux(ds: xr.Dataset):
    """Flux through every side hole vs time (positive outward, lumen -> annulus), one panel per stented
    model, lines coloured by the hole's axial position."""
    models = _models(ds, stented_only=True, var="hole_flux")
    n = max(len(models), 1)
    fig, axes = plt.subplots(n, 1, figsize=(6.4, 1.9 * n + 0.6), sharex=True, sharey=True, squeeze=False)
    axes = axes[:, 0]
    L = float(ds["z"].max()) * MM
    norm = matplotlib.colors.Normalize(0.0, L)
    cmap = plt.get_cmap("viridis")
    for ax, (m, lab) in zip(axes, models):
        d = ds.sel(model=m)
        hz, hs = d["hole_z"].values, d["hole_side"].values
        for k in np.flatnonzero(np.isfinite(hz)):
            ax.plot(ds["time"], d["hole_flux"].isel(hole=k) * MM3_S, color=cmap(norm(hz[k] * MM)), lw=1.0,
                    ls="-" if hs[k] > 0 else ":")
        ax.axhline(0.0, color="k", lw=0.6)
        ax.set_title(f"{lab} ({int(np.isfinite(hz).sum())} holes in the model)", loc="left")
        ax.set_ylabel("hole flux (mm³/s)")
    axes[-1].set_xlabel("time (s)")
    fig.colorbar(matplotlib.cm.ScalarMappable(norm=norm, cmap=cmap), ax=list(axes), label="hole position z (mm)")
    fig.suptitle("Flow rate through each side hole (positive: from the stent lumen outward)")
    return fig


# ---------------------------------------------------------------------------------------------- Table 1
TABLE1_SIDECAR = Contract("mesh sidecar", attrs=("model", "level", "symmetry", "cells", "cells_total", "hole_pair_z",
                                                "hole_channels_found"))   # what table1 reads


def table1(cfg: dict, sidecars) -> list[dict]:
    """Rows of Table 1 (config models) with hole-pair positions and element counts of the meshes."""
    info = {}
    for p in sidecars:
        d = read_json(p, TABLE1_SIDECAR)
        info[str(d["model"])] = d
    rows = []
    for m in sorted(cfg["models"], key=lambda s: (len(s), s)):
        c = cfg["models"][m]
        d = info.get(m, {})
        cells = d.get("cells", {})
        rows.append({
            "model": m, "label": c["label"],
            "hole_pair_spacing_mm": f"{c['hole_pair_spacing'] * MM:g}",
            "side_holes": c["holes"],
            "hole_pairs_z_mm": " ".join(f"{z * MM:g}" for z in d.get("hole_pair_z", [])),
            "hole_channels_found": d.get("hole_channels_found", ""),
            "symmetry": d.get("symmetry", ""), "mesh_level": d.get("level", ""),
            "elements_total": d.get("cells_total", ""),
            "elements_fluid": cells.get("fluid", ""), "elements_ureter": cells.get("ureter", ""),
            "elements_stent": cells.get("stent", 0 if d else ""),
        })
    return rows


TABLE1_HEAD = {"model": "Model", "label": "Label", "hole_pair_spacing_mm": "Hole-pair spacing (mm)",
               "side_holes": "Side holes", "hole_pairs_z_mm": "Hole-pair positions z (mm)",
               "hole_channels_found": "Hole channels in mesh", "symmetry": "Symmetry", "mesh_level": "Mesh",
               "elements_total": "Elements", "elements_fluid": "fluid", "elements_ureter": "ureter",
               "elements_stent": "stent"}


def write_table1(rows: list[dict], csv_path=None, md_path=None) -> None:
    """Table 1 as CSV and Markdown, atomically (data.tables.write_table)."""
    write_table(rows, csv_path, md_path, header=[TABLE1_HEAD.get(c, c) for c in rows[0]])
