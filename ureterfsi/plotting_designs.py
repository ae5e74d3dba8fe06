"""Figures of the design studies (ureterfsi.designs datasets): each quantity against each parameter, and for a
sample the standardised regression coefficients (SRC_j = b_j s_xj / s_y of a linear least-squares fit)."""
from __future__ import annotations

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import xarray as xr  # noqa: E402

from .designs import PARAMETERS, standardised_regression_coefficients  # noqa: E402

QUANTITIES = ("peak_outlet_flux", "mean_outlet_flux", "backflow_volume", "hole_exchange_fraction",
              "stent_lumen_fraction", "peak_stent_von_mises", "peak_wall_displacement")


def _parameters(ds: xr.Dataset) -> list:
    return [q for q in PARAMETERS if q in ds.coords]


def _flat(ds: xr.Dataset) -> xr.Dataset:
    """One `point` dimension whatever the layout (grid dimensions stacked)."""
    if "design" in ds.dims:
        return ds.rename({"design": "point"})
    return ds.stack(point=_parameters(ds))


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


def sensitivity_figure(ds: xr.Dataset):
    """Standardised regression coefficients of each quantity on the parameters (R^2 of the fit in the title)."""
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
