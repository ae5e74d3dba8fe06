"""Figures of the fidelity ladder (ureterfsi.analyses.ladder): the speed-accuracy trade of its rungs and their figure
quantities over each other."""
from __future__ import annotations

import matplotlib.pyplot as plt
import numpy as np
import xarray as xr

from ureterfsi.analyses.ladder import common_holes
from ureterfsi.plotting.style import styled

LADDER_OVERLAY = {"outlet_flux": "outlet flow (Fig. 4)", "inlet_flux": "inlet flow",
                  "hole_flux": "side-hole flow (Fig. 11)", "stent_max_von_mises": "stent's largest von Mises (Fig. 10)",
                  "max_wall_displacement": "wall's largest radial displacement",
                  "wall_radial_displacement": "wall's radial displacement (Fig. 5)"}


@styled
def ladder_overlay(runs: dict, reference: str):
    """The figure quantities of every rung of the ladder over each other (`runs`: rung -> run dataset): the time
    series, the side hole whose flow is largest in the `reference` run (matched by position in the others), and the
    wall's radial displacement at the last probe time; the reference solid, the other rungs dashed."""
    ref = runs[reference]
    names = [reference] + [r for r in runs if r != reference]
    fig, axs = plt.subplots(2, 3, figsize=(12, 6.4), layout="constrained")
    hole = int(np.abs(ref["hole_flux"]).max("time").argmax()) if ref.sizes.get("hole") else None
    for ax, q in zip(axs.flat, LADDER_OVERLAY):
        attrs = ref[q].attrs
        for k, r in enumerate(names):
            run, style = runs[r], dict(lw=1.6, color="k") if r == reference else dict(lw=1.2, ls="--", color=f"C{k}")
            if q == "hole_flux":
                if hole is None:
                    continue
                in_ref, in_run = common_holes(ref, run)
                if hole not in in_ref:
                    continue
                ax.plot(run["time"], run[q].isel(hole=in_run[in_ref.index(hole)]), label=r, **style)
            elif q == "wall_radial_displacement":
                last = run["probe_time"].values[-1]
                ax.plot(run["z"] * 1e3, run[q].sel(probe_time=last), label=f"{r} ({last:g} s)", **style)
            else:
                ax.plot(run["time"], run[q], label=r, **style)
        title = LADDER_OVERLAY[q]
        if q == "hole_flux" and hole is not None:
            title += f", hole at z = {float(ref['hole_z'][hole]) * 1e3:.2f} mm"
        ax.set_title(title, fontsize=9)
        ax.set_ylabel(f"{q.replace('_', ' ')} ({attrs.get('units', '-')})", fontsize=8)
        ax.set_xlabel("z (mm)" if q == "wall_radial_displacement" else "time (s)", fontsize=8)
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=7)
    fig.suptitle(f"Fidelity ladder: the rungs' figure quantities over each other (reference '{reference}', solid)",
                 fontsize=10)
    return fig


@styled
def ladder_pareto(ds: xr.Dataset):
    """Speed-accuracy trade of the fidelity ladder: wall time of each rung against its error for every
    quantity (ureterfsi.analyses.ladder); the reference rung (error 0) is drawn on the lower axis limit."""
    fig, ax = plt.subplots(figsize=(9.5, 4.8))
    errors = ds["error"].values
    positive = errors[np.isfinite(errors) & (errors > 0)]
    floor = 10 ** np.floor(np.log10(positive.min())) / 3 if positive.size else 1e-6
    markers = "osD^vP*Xh<>"
    for k, q in enumerate(ds["quantity"].values):
        e = ds["error"].sel(quantity=q).values
        ax.scatter(ds["wall_time"].values, np.where(e > 0, e, floor), marker=markers[k % len(markers)],
                   s=40, alpha=0.8, label=str(q).replace("_", " "))
    for r in ds["rung"].values:
        row = ds.sel(rung=r)
        e = row["error"].values
        top = np.nanmax(e) if np.isfinite(e).any() and np.nanmax(e) > 0 else floor
        ax.annotate(str(r), (float(row["wall_time"]), top), textcoords="offset points", xytext=(4, 6), fontsize=8)
    ax.set_xscale("log")
    ax.set_yscale("log")
    if "tolerance" in ds:
        for tol in sorted(set(float(t) for t in ds["tolerance"].values)):
            ax.axhline(tol, color="0.4", ls=":", lw=1)
            ax.annotate(f"scene tolerance {tol:g}", (0.01, tol), xycoords=("axes fraction", "data"), xytext=(0, 2),
                        textcoords="offset points", fontsize=8, color="0.3")
    ax.set_xlabel("wall time of the run (s)")
    ax.set_ylabel(f"relative error vs '{ds.attrs.get('reference', 'reference')}' (-)")
    ax.set_title(f"Fidelity ladder, model {ds.attrs.get('model', '?')}, first {ds.attrs.get('window_s', '?')} s "
                 f"(reference on the lower edge)", fontsize=10)
    ax.legend(fontsize=7, loc="center left", bbox_to_anchor=(1.01, 0.5))
    ax.grid(True, which="both", alpha=0.3)
    fig.tight_layout()
    return fig
