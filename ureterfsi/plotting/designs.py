"""Figures of the design studies (ureterfsi.designs.results datasets): each quantity against each parameter; for a
full-factorial grid a map over two parameters; for a sample a sensitivity ranking: the Sobol' indices S1, ST
of a Saltelli design, else the standardised regression coefficients (SRC_j = b_j s_xj / s_y of a linear
least-squares fit)."""
from __future__ import annotations

import itertools
import textwrap

import matplotlib.pyplot as plt
import numpy as np
import xarray as xr

from ureterfsi.designs.results import QUANTITIES, standardised_regression_coefficients
from ureterfsi.designs.space import PARAMETERS, map_parameters
from ureterfsi.plotting.style import styled


def _parameters(ds: xr.Dataset) -> list:
    return [q for q in PARAMETERS if q in ds.coords]


def _flat(ds: xr.Dataset) -> xr.Dataset:
    """One `point` dimension whatever the layout (grid dimensions stacked)."""
    if "design" in ds.dims:
        return ds.rename({"design": "point"})
    # xarray cannot stack a variable with an empty dimension (hole: 0 in a study of a stent-free model)
    return ds.drop_dims([d for d, n in ds.sizes.items() if n == 0]).stack(point=_parameters(ds))


@styled
def parameters_figure(ds: xr.Dataset):
    """Each scalar quantity (rows) against each parameter (columns), every point drawn."""
    params, flat = _parameters(ds), _flat(ds)
    quantities = [q for q in QUANTITIES if q in ds and np.isfinite(ds[q].values).any()]
    fig, axes = plt.subplots(len(quantities), len(params), figsize=(2.6 * len(params) + 0.8, 1.9 * len(quantities)),
                             squeeze=False)
    for j, p in enumerate(params):
        x = np.asarray(flat[p].values, float)
        for i, q in enumerate(quantities):
            ax = axes[i, j]
            ax.plot(x, flat[q].values, "o", ms=4)
            if j == 0:
                ax.set_ylabel(f"{q.replace('_', ' ')}\n[{ds[q].attrs['units']}]")
            if i == len(quantities) - 1:
                ax.set_xlabel(f"{p.replace('_', ' ')} [{PARAMETERS[p].units}]")
    fig.suptitle(ds.attrs.get("title", ""))
    return fig


def _label(name: str) -> str:
    return name.replace("_", " ")


@styled
def map_figure(ds: xr.Dataset):
    """Each quantity (rows) as a map over the first two grid parameters with two or more values (x, y; cells
    centred on the design points, which are marked), one column per combination of the values of the other
    such parameters; a colour scale per quantity, in its units."""
    grid = {d: ds[d].values for d in ds["point_id"].dims}
    varied = map_parameters(grid)
    if len(varied) < 2:
        raise ValueError(f"a map needs two grid parameters with two or more values, got {varied}")
    px, py, others = varied[0], varied[1], varied[2:]
    fixed = {d: grid[d][0] for d in grid if d not in varied}
    columns = list(itertools.product(*(grid[o] for o in others)))
    quantities = [q for q in QUANTITIES if q in ds and np.isfinite(ds[q].values).any()]
    fig, axes = plt.subplots(len(quantities), len(columns), figsize=(3.6 * len(columns) + 0.6, 2.8 * len(quantities)),
                             squeeze=False, constrained_layout=True)
    x, y = np.asarray(grid[px], float), np.asarray(grid[py], float)
    xx, yy = np.meshgrid(x, y)
    for i, q in enumerate(quantities):
        da = ds[q].isel({d: 0 for d in fixed})
        vmin, vmax = float(np.nanmin(da.values)), float(np.nanmax(da.values))
        for j, combo in enumerate(columns):
            ax = axes[i, j]
            c = da.sel(dict(zip(others, combo))).transpose(py, px).values
            mesh = ax.pcolormesh(x, y, np.ma.masked_invalid(c), shading="nearest", vmin=vmin, vmax=vmax)
            ax.plot(xx.ravel(), yy.ravel(), "k.", ms=5)
            fig.colorbar(mesh, ax=ax, label=f"{_label(q)} [{ds[q].attrs['units']}]")
            ax.set_xlabel(f"{_label(px)} [{PARAMETERS[px].units}]")
            ax.set_ylabel(f"{_label(py)} [{PARAMETERS[py].units}]")
            if others:
                ax.set_title(", ".join(f"{_label(o)} = {v:g} {PARAMETERS[o].units}" for o, v in zip(others, combo)),
                             fontsize=8)
    at = ", ".join(f"{_label(d)} = {float(v):g} {PARAMETERS[d].units}" for d, v in fixed.items())
    title = ds.attrs.get("title", "") + (f"\n{at}" if at else "")
    width = int(13 * fig.get_figwidth())            # characters of 9 pt text across the figure
    fig.suptitle("\n".join(textwrap.fill(line, width) for line in title.split("\n")), fontsize=9)
    return fig


@styled
def sobol_figure(ds: xr.Dataset):
    """First-order and total Sobol' indices S1, ST of each quantity (panels) per parameter, bars with their 95 %
    confidence intervals (ureterfsi.designs.results.sobol_indices)."""
    params = [str(p) for p in ds["parameter"].values]
    quantities = [str(q) for q in ds["quantity"].values if np.isfinite(ds["sobol_total"].sel(quantity=q).values).any()]
    n = max(len(quantities), 1)
    fig, axes = plt.subplots(1, n, figsize=(2.6 * n + 1.2, 0.5 * len(params) + 1.8), squeeze=False, sharey=True)
    pos = np.arange(len(params))
    for ax, q in zip(axes[0], quantities):
        for k, (name, label, shift) in enumerate((("sobol_first_order", "S1", -0.2), ("sobol_total", "ST", 0.2))):
            ax.barh(pos + shift, ds[name].sel(quantity=q).values, height=0.38, label=label,
                    xerr=ds[f"{name}_conf"].sel(quantity=q).values, capsize=2)
        ax.set_yticks(pos, [_label(p) for p in params])
        ax.set_title(_label(q), fontsize=9)
        ax.set_xlabel("Sobol' index")
    axes[0, 0].legend(fontsize=8)
    fig.suptitle(ds.attrs.get("title", ""), fontsize=9)
    return fig


@styled
def sensitivity_figure(ds: xr.Dataset):
    """The Sobol' indices of a Saltelli design (sobol_figure); else the standardised regression coefficients of
    each quantity on the parameters (R^2 of the fit in the title)."""
    if "sobol_total" in ds:
        return sobol_figure(ds)
    params, flat = _parameters(ds), _flat(ds)
    quantities = [q for q in QUANTITIES if q in ds and np.isfinite(ds[q].values).any()]
    fig, axes = plt.subplots(1, len(quantities), figsize=(2.4 * len(quantities), 2.6), squeeze=False, sharey=True)
    for ax, q in zip(axes[0], quantities):
        src, r2 = standardised_regression_coefficients(flat, params, q)
        ax.barh(range(len(params)), src)
        ax.set_yticks(range(len(params)), [p.replace("_", " ") for p in params])
        ax.set_title(f"{q.replace('_', ' ')}\nR² = {r2:.2f}")
        ax.set_xlabel("SRC")
    return fig


PASSAGE = ("hole_net_volume", "hole_gross_exchange_volume", "hole_wall_tawss", "hole_wall_low_wss_area_fraction")


@styled
def passage_figure(ds: xr.Dataset):
    """Per side hole against its axial position (ureterfsi.designs.passage): the net volume out of the stent, the
    gross exchange, TAWSS and the low-WSS area fraction of its wall (rows); one column per value of the study's
    first parameter, one line per point (its other parameters in the legend); filled markers upstream of the
    obstruction, open ones downstream, the obstruction's centre dashed; the references' holes in grey."""
    params, flat = (list(ds["point_id"].dims) if "point_id" in ds else _parameters(ds)), _flat(ds)
    first = params[0]
    values = list(dict.fromkeys(np.asarray(flat[first].values, float).tolist()))
    fig, axes = plt.subplots(len(PASSAGE), len(values), figsize=(3.4 * len(values) + 1.0, 2.1 * len(PASSAGE)),
                             squeeze=False, sharex=True, constrained_layout=True)
    for k in range(flat.sizes["point"]):
        pt = flat.isel(point=k)
        j = values.index(float(pt[first]))
        z = np.asarray(pt["hole_z"].values, float) * 1e3
        up = np.asarray(pt["hole_proximal"].values, float) == 1
        label = ", ".join(f"{_label(p)} {float(pt[p]):g}" for p in params[1:]) or None
        for i, q in enumerate(PASSAGE):
            ax, y = axes[i, j], np.asarray(pt[q].values, float)
            order = np.argsort(z)
            line, = ax.plot(z[order], y[order], "-", lw=0.8, label=label if i == 0 else None)
            ax.plot(z[up], y[up], "o", ms=4, color=line.get_color())
            ax.plot(z[~up], y[~up], "o", ms=4, mfc="none", color=line.get_color())
            if np.isfinite(float(pt["obstruction_position"])):
                ax.axvline(float(pt["obstruction_position"]) * 1e3, ls="--", lw=0.6, color=line.get_color())
    for j, v in enumerate(values):
        axes[0, j].set_title(f"{_label(first)} = {v:g} {PARAMETERS[first].units}", fontsize=8)
        axes[-1, j].set_xlabel("hole position z [mm]")
        if len(params) > 1:
            axes[0, j].legend(fontsize=6)
    for i, q in enumerate(PASSAGE):
        axes[i, 0].set_ylabel(f"{_label(q)}\n[{ds[q].attrs['units']}]", fontsize=8)
    fig.suptitle(ds.attrs.get("title", "") + "\nfilled: upstream of the obstruction; open: downstream", fontsize=9)
    return fig
