"""The paper's question, does the number of side holes change the outlet flow, and when, answered from the design
studies' datasets (`results/designs/<study>.nc`): for each study varying `hole_pair_spacing` on a full-factorial
grid, at every combination of its other parameters, how far apart the spacings' outlet flows lie,

    outlet_flux_spread = max_t (max_s Q_s(t) - min_s Q_s(t)) / max_{s,t} |Q_s(t)|,

with Q_s the outlet flux at spacing s, and the net outlet volume int Q_s dt of each spacing over the window (its
`mean_outlet_flux`, from the run file, times the window), beside the conditions that hold it (the study's obstruction
and ends) and the window (docs/design-passage.md)::

    .venv/bin/python -m ureterfsi.designs.question results/designs/occlusion_holes.nc results/designs/voiding_reflux.nc
"""
from __future__ import annotations

import argparse
import itertools
import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import xarray as xr

from ureterfsi.data.checked import open_netcdf
from ureterfsi.data.provenance import atomic_path
from ureterfsi.designs.results import DESIGN_DATASET

SPACING = "hole_pair_spacing"


@dataclass
class SpacingEffect:
    """One row: a study's scene at fixed values of its other parameters, and what the hole spacing does there."""
    study: str
    values: dict          # the other parameters' values (SI)
    condition: str
    window: tuple[float, float]
    spacings: list[float]
    outlet_flux_spread: float
    outlet_volumes: list[float]
    peak_outlet_flux: float


def asks(st) -> bool:
    """Whether a study (ureterfsi.designs.space.Study) answers the question: a full-factorial grid varying the
    spacing."""
    return st.kind == "full_factorial" and SPACING in st.parameters


def outlet_flux_spread(q: np.ndarray) -> float:
    """max_t (max_s q - min_s q) / max |q| of the outlet fluxes q[s, t] (module docstring); NaN without flow."""
    q = q[:, np.isfinite(q).any(axis=0)]
    peak = np.abs(q).max(initial=0.0, where=np.isfinite(q))
    if not peak > 0:
        return np.nan
    return float(np.nanmax(np.nanmax(q, axis=0) - np.nanmin(q, axis=0)) / peak)


def conditions(ds: xr.Dataset, sel: dict) -> str:
    """The conditions of a row: the obstruction at the selected points, the study's ends (its base overlay, the
    dataset's `study_base`) and the selected values of the other parameters, in SI units."""
    parts = []
    if "obstruction" in ds:
        kind = np.unique(np.asarray(ds["obstruction"].sel(sel).values, str))
        where = np.unique(np.round(np.asarray(ds["obstruction_position"].sel(sel).values, float), 6))
        parts.append(", ".join(kind) + ("" if "none" in kind else " at " + ", ".join(f"{z:g} m" for z in where)))
    ends = json.loads(ds.attrs.get("study_base", "{}")).get("ends", {})
    if ends:
        parts.append("ends: " + ", ".join(f"{end} {v['condition']}" for end, v in ends.items() if "condition" in v))
    parts += [f"{k} = {v:g} {ds[k].attrs.get('units', '')}".rstrip() for k, v in sel.items()]
    return "; ".join(parts)


def spacing_effects(ds: xr.Dataset) -> list[SpacingEffect]:
    """The rows of one study's dataset: one per combination of the parameters other than the spacing (none if the
    study does not vary the spacing on a grid)."""
    if SPACING not in ds["outlet_flux"].dims:
        return []
    others = [d for d in ds["outlet_flux"].dims if d not in (SPACING, "time")]
    t = ds["time"].values.astype(float)
    rows = []
    for values in itertools.product(*(ds[d].values.tolist() for d in others)):
        sel = dict(zip(others, values))
        q = ds["outlet_flux"].sel(sel).transpose(SPACING, "time").values.astype(float)
        rows.append(SpacingEffect(
            study=ds.attrs.get("study", "?"), values=sel, condition=conditions(ds, sel),
            window=(float(t[0]), float(t[-1])),
            spacings=ds[SPACING].values.astype(float).tolist(), outlet_flux_spread=outlet_flux_spread(q),
            outlet_volumes=(ds["mean_outlet_flux"].sel(sel).transpose(SPACING).values * (t[-1] - t[0])).tolist(),
            peak_outlet_flux=float(np.nanmax(np.abs(q)))))
    return rows


def table(rows: list[SpacingEffect]) -> str:
    """A Markdown table of the rows (SI units)."""
    lines = ["| study | scene | window (s) | hole-pair spacings (m) | outlet flux spread (1) | peak outlet flux (m3/s) "
             "| net outlet volume per spacing (m3) |", "|---|---|---|---|---|---|---|"]
    for r in rows:
        vols = ", ".join(f"{v:.3g}" for v in r.outlet_volumes)
        lines.append(f"| {r.study} | {r.condition} | {r.window[0]:g}-{r.window[1]:g} | "
                     f"{', '.join(f'{s:g}' for s in r.spacings)} | {r.outlet_flux_spread:.3g} | "
                     f"{r.peak_outlet_flux:.3g} | {vols} |")
    return "\n".join(lines)


def datasets_table(datasets) -> str:
    """The table of the rows of every dataset (paths), each checked as a design dataset."""
    return table([r for p in datasets for r in spacing_effects(open_netcdf(p, DESIGN_DATASET))])


def write_table(datasets, path) -> None:
    """The table of the datasets (paths) written to `path` (atomically), under a line naming them."""
    text = ("Does the number of side holes change the outlet flow? (ureterfsi.designs.question; "
            f"from {', '.join(str(p) for p in datasets)})\n\n{datasets_table(datasets)}\n")
    with atomic_path(path) as tmp:
        Path(tmp).write_text(text)


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("datasets", nargs="+", help="design study datasets (results/designs/<study>.nc)")
    args = ap.parse_args(argv)
    print(datasets_table(args.datasets))


if __name__ == "__main__":
    main()
