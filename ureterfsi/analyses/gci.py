"""Grid Convergence Index (GCI) of Roache, in the procedure standardised by

    Celik, I. B., Ghia, U., Roache, P. J., Freitas, C. J., Coleman, H. & Raad, P. E. (2008),
    "Procedure for estimation and reporting of uncertainty due to discretization in CFD applications",
    J. Fluids Eng. 130(7), 078001, doi:10.1115/1.2960953

applied to the mesh-convergence dataset of the study (ureterfsi.analyses.aggregate.combine_levels, paper §3.1).

The procedure (Celik et al. 2008, steps 1-5), for a quantity phi computed on three grids numbered fine to
coarse, 1 (finest), 2, 3:

1. representative cell size       h = (V / N)^(1/d)           (V total volume or area, N cells, d dimension)
2. refinement ratios              r21 = h2 / h1,  r32 = h3 / h2     (Celik et al. recommend r > 1.3)
3. apparent order p, from the fixed-point iteration
                                  p = | ln|eps32 / eps21| + q(p) | / ln r21
                                  q(p) = ln( (r21^p - s) / (r32^p - s) ),   s = sign(eps32 / eps21)
                                  eps21 = phi2 - phi1,  eps32 = phi3 - phi2      (q = 0 when r21 = r32)
4. extrapolated value             phi_ext21 = (r21^p phi1 - phi2) / (r21^p - 1)
5. error estimates                e_a21   = | (phi1 - phi2) / phi1 |              approximate relative error
                                  e_ext21 = | (phi_ext21 - phi1) / phi_ext21 |    extrapolated relative error
                                  GCI_fine21 = Fs e_a21 / (r21^p - 1),  Fs = 1.25 (three grids)

plus, for the asymptotic-range check of Roache, the coarse pair GCI32 = Fs e_a32 / (r32^p - 1) with
e_a32 = |(phi2 - phi3) / phi2| and the ratio GCI32 / (r21^p GCI21), which is ~1 in the asymptotic range.
The relative errors and GCIs are fractions (0.02 = 2 %).

Convergence diagnosis from R = eps21 / eps32 (Stern et al. 2001; Celik et al. 2008 flag eps32/eps21 < 0):
  "monotone"       0 < R < R_max: the full procedure applies;
  "oscillatory"    R < 0: computed as in Celik et al.'s own oscillatory example (their Table 1, with
                   s = -1), to be read with care;
  "divergent"      R >= R_max (including eps32 = 0 with eps21 != 0): no power law phi0 + C h^p with p > 0
                   fits the data, no extrapolation: p, phi_ext, GCI are NaN;
  "identical"      phi1 = phi2 = phi3: no discretisation error detectable; p is NaN, phi_ext = phi1 and the
                   errors and GCIs are 0;
  "indeterminate"  phi1 = phi2 but phi3 differs (R = 0): the order is unbounded; p, phi_ext, GCI are NaN.
with R_max = ln r21 / ln r32, which is the classical R_max = 1 for a constant refinement ratio. For unequal
ratios the classical bound misclassifies: a monotone sequence phi0 + C h^p (p > 0) has
eps32/eps21 = r21^p (r32^p - 1)/(r21^p - 1), which decreases to ln r32/ln r21 as p -> 0, so R may exceed 1
for an exactly converging sequence when r32 < r21 (e.g. h = 1, 1.5, 1.8 and p = 2: R = 1.26), and R < 1 may
have no p > 0 when r32 > r21. Beyond R_max, Celik et al.'s |.| in the order equation would return the
mirror image of a negative order and a meaningless extrapolation.
If the fixed-point iteration does not converge (it can diverge when r21 and r32 differ much) or gives
p = 0, p and everything derived from it are NaN and `note` says so; the diagnosis keeps the convergence type.
Legitimate data never raise: only malformed input (not three finite values, non-positive or repeated h)
raises ValueError.

Worked example of Celik et al. 2008, Table 1, first column (2D, N = 18000 / 8000 / 4500,
phi = 6.063 / 5.972 / 5.863): this module gives p = 1.534, phi_ext21 = 6.1685, e_a21 = 1.50 %,
e_ext21 = 1.71 %, GCI_fine21 = 2.175 % (published 1.53, 6.1685, 1.5 %, 1.7 %, 2.04 %). The published GCI is
not what the paper's own formula gives with its own p and phi_ext: GCI_fine21 = Fs e_a21/(r21^p - 1) =
Fs (phi_ext21 - phi1)/phi1 = 1.25 x 0.1055/6.063 = 2.175 %. For the other two columns (N = 18000 / 4500 /
980; a monotone case with p = 0.75 and the oscillatory case) p, phi_ext21, e_a21 and GCI_fine21 agree with
the published values to the printed digits (tests/analyses/test_gci.py).

For the study (gci_dataset): the three finest levels of the mesh-convergence dataset, h = (V/N)^(1/3) with
N the cell count of each level's mesh and V the volume of the whole mesh, which is the same for every level
(the analytic volume of the mesh sidecar when given, else h = N^(-1/3), i.e. V = 1: only the ratios r21,
r32 enter the GCI).
"""
from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np
import xarray as xr

from ureterfsi.data.checked import Contract, read_json
from ureterfsi.data.cf import at_z, attach, cf_attrs, cf_meta, gci_quantity_variables, gci_variables
from ureterfsi.data.provenance import provenance_attrs
from ureterfsi.data.tables import write_table

# what the readers of a GCI dataset (table_gci) rely on
GCI_DATASET = Contract("GCI dataset", attrs=("fine_level", "medium_level", "coarse_level", "safety_factor"),
                       variables=("quantity", "level", "cells", "h", "r21", "r32", "apparent_order", "gci_fine21",
                                  "diagnosis", "probe_z"))
SIDECAR = Contract("mesh sidecar", attrs=("measure", "subdomain_measure"))   # what mesh_measure reads
SAFETY_FACTOR = 1.25                      # Celik et al. 2008 (and Roache) for three or more grids
DEFAULT_POINTS_Z = (0.0125, 0.025, 0.0375)   # m: probe-line points of the GCI (quarter, half, three quarters of L)
DEFAULT_SCALARS = ("peak_outlet_flux", "peak_stent_max_von_mises", "peak_outlet_hole_flux", "outlet_hole_peak_velocity")
REFERENCE = ("Celik, Ghia, Roache, Freitas, Coleman & Raad 2008, Procedure for estimation and reporting of "
             "uncertainty due to discretization in CFD applications, J. Fluids Eng. 130, 078001, "
             "doi:10.1115/1.2960953")
DIAGNOSES = ("monotone", "oscillatory", "divergent", "identical", "indeterminate")


def representative_cell_size(n_cells, measure=1.0, dim: int = 3):
    """h = (measure / N)^(1/dim) (Celik et al. 2008, step 1): measure is the total volume (dim 3) or area
    (dim 2) of the mesh. Arrays of cell counts give arrays of h."""
    n = np.asarray(n_cells, dtype=float)
    if np.any(~np.isfinite(n)) or np.any(n <= 0):
        raise ValueError(f"cell counts must be positive, got {n_cells!r}")
    if not measure > 0:
        raise ValueError(f"the mesh measure must be positive, got {measure!r}")
    h = (float(measure) / n) ** (1.0 / dim)
    return float(h) if h.ndim == 0 else h


@dataclass(frozen=True)
class GCIResult:
    """Three-grid GCI of one quantity (Celik et al. 2008). Index 1 is the finest grid, 3 the coarsest.

    Relative errors and GCIs are fractions. `order` gives, for grids 1, 2, 3, the position of that grid
    in the input sequences."""

    h: tuple                       # (h1, h2, h3), fine to coarse
    phi: tuple                     # (phi1, phi2, phi3)
    order: tuple                   # input positions of grids 1, 2, 3
    r21: float
    r32: float
    eps21: float                   # phi2 - phi1
    eps32: float                   # phi3 - phi2
    convergence_ratio: float       # R = eps21 / eps32
    apparent_order: float          # p (NaN if undefined, see diagnosis and note)
    iterations: int                # fixed-point iterations for p (0 if not iterated)
    phi_ext21: float
    phi_ext32: float
    e_a21: float
    e_a32: float
    e_ext21: float
    gci_fine21: float
    gci32: float
    asymptotic_ratio: float        # GCI32 / (r21^p GCI21), ~1 in the asymptotic range
    diagnosis: str                 # one of DIAGNOSES
    note: str
    safety_factor: float

    def as_dict(self) -> dict:
        return asdict(self)


def _apparent_order(r21, r32, eps21, eps32, tol=1e-14, maxiter=1000):
    """Fixed-point iteration p <- |ln|eps32/eps21| + q(p)| / ln r21 (Celik et al. 2008, step 3), started at
    q = 0. Returns (p, iterations) or (nan, iterations) when it does not converge."""
    ratio = eps32 / eps21
    s = 1.0 if ratio > 0 else -1.0
    a = math.log(abs(ratio))
    ln21 = math.log(r21)
    p = abs(a) / ln21
    if r21 == r32:                       # q(p) = 0 exactly
        return p, 1
    for k in range(1, maxiter + 1):
        try:
            q = math.log((r21 ** p - s) / (r32 ** p - s))
        except (OverflowError, ValueError, ZeroDivisionError):
            return math.nan, k
        p_new = abs(a + q) / ln21
        if not math.isfinite(p_new):
            return math.nan, k
        if abs(p_new - p) <= tol * max(1.0, p):
            return p_new, k
        p = p_new
    return math.nan, maxiter


def _rel(num, den):
    return abs(num / den) if den != 0 else math.nan


def three_grid_gci(h, phi, safety_factor: float = SAFETY_FACTOR) -> GCIResult:
    """GCI of one quantity from three grids (Celik et al. 2008; equations in the module docstring).

    h: representative cell sizes, phi: the solutions, in any order (sorted here by h, finest first).
    Never raises for legitimate data: see the module docstring for the diagnosis of non-monotone data."""
    h = np.asarray(h, dtype=float).ravel()
    phi = np.asarray(phi, dtype=float).ravel()
    if h.size != 3 or phi.size != 3:
        raise ValueError(f"three grids needed, got {h.size} cell sizes and {phi.size} values")
    if not (np.all(np.isfinite(h)) and np.all(h > 0)):
        raise ValueError(f"cell sizes must be positive and finite, got {h.tolist()}")
    if not np.all(np.isfinite(phi)):
        raise ValueError(f"solutions must be finite, got {phi.tolist()}")
    order = np.argsort(h, kind="stable")
    h1, h2, h3 = (float(x) for x in h[order])
    p1, p2, p3 = (float(x) for x in phi[order])
    if not (h1 < h2 < h3):
        raise ValueError(f"the three cell sizes must differ, got {h.tolist()}")
    fs = float(safety_factor)
    r21, r32 = h2 / h1, h3 / h2
    eps21, eps32 = p2 - p1, p3 - p2
    e_a21, e_a32 = _rel(p1 - p2, p1), _rel(p2 - p3, p2)
    nan = math.nan
    out = dict(h=(h1, h2, h3), phi=(p1, p2, p3), order=tuple(int(i) for i in order), r21=r21, r32=r32,
               eps21=eps21, eps32=eps32, convergence_ratio=nan, apparent_order=nan, iterations=0,
               phi_ext21=nan, phi_ext32=nan, e_a21=e_a21, e_a32=e_a32, e_ext21=nan, gci_fine21=nan, gci32=nan,
               asymptotic_ratio=nan, diagnosis="", note="", safety_factor=fs)

    if eps21 == 0 and eps32 == 0:
        out.update(diagnosis="identical", phi_ext21=p1, phi_ext32=p2, e_ext21=0.0 if p1 != 0 else nan,
                   gci_fine21=0.0 if p1 != 0 else nan, gci32=0.0 if p2 != 0 else nan,
                   note="identical solutions on the three grids: no discretisation error detectable, "
                        "apparent order undefined")
        return GCIResult(**out)
    if eps21 == 0:
        out.update(convergence_ratio=0.0, diagnosis="indeterminate",
                   note="the two finest solutions are identical but the coarse one differs: apparent order "
                        "unbounded, no extrapolation")
        return GCIResult(**out)
    if eps32 == 0:
        out.update(convergence_ratio=math.copysign(math.inf, eps21), diagnosis="divergent",
                   note="the two coarsest solutions are identical but the fine one differs: the difference "
                        "grows with refinement, no extrapolation")
        return GCIResult(**out)
    R = eps21 / eps32
    out["convergence_ratio"] = R
    r_max = math.log(r21) / math.log(r32)     # 1 for r21 = r32; the bound of a power law with p > 0
    if R >= r_max:
        out.update(diagnosis="divergent",
                   note=f"R = eps21/eps32 = {R:.4g} >= ln r21/ln r32 = {r_max:.4g}: the difference grows with "
                        f"refinement (no power law with p > 0), no extrapolation")
        return GCIResult(**out)
    out["diagnosis"] = "monotone" if R > 0 else "oscillatory"

    p, its = _apparent_order(r21, r32, eps21, eps32)
    out["iterations"] = its
    if not (math.isfinite(p) and p > 0):
        out["note"] = (f"the fixed-point iteration for the apparent order did not converge ({its} iterations)"
                       if not math.isfinite(p) else "apparent order 0: no extrapolation")
        return GCIResult(**out)
    out["apparent_order"] = p
    try:
        a21, a32 = r21 ** p, r32 ** p
    except OverflowError:
        out.update(apparent_order=nan, note=f"apparent order {p:.4g} overflows r^p: no extrapolation")
        return GCIResult(**out)
    phi_ext21 = (a21 * p1 - p2) / (a21 - 1.0)
    phi_ext32 = (a32 * p2 - p3) / (a32 - 1.0)
    gci21 = fs * e_a21 / (a21 - 1.0)
    gci32 = fs * e_a32 / (a32 - 1.0)
    ratio = gci32 / (a21 * gci21) if gci21 > 0 else nan
    out.update(phi_ext21=phi_ext21, phi_ext32=phi_ext32, e_ext21=_rel(phi_ext21 - p1, phi_ext21),
               gci_fine21=gci21, gci32=gci32, asymptotic_ratio=ratio)
    if out["diagnosis"] == "oscillatory":
        out["note"] = f"oscillatory convergence (R = {R:.4g}): Celik et al.'s procedure with s = -1, read with care"
    return GCIResult(**out)


# ------------------------------------------------------------------------------------------- datasets
def mesh_measure(sidecar) -> tuple[float, int]:
    """(total analytic measure, dimension) of a mesh from its JSON sidecar (ureterfsi.mesh.build): the volume of
    a 3D mesh (m3, d = 3) or the area of an axisymmetric r-z mesh (m2, d = 2). The analytic measure is the
    same for every mesh level, as h = (V/N)^(1/d) wants."""
    info = read_json(sidecar, SIDECAR)
    total = float(sum(v["analytic"] for v in info["subdomain_measure"].values()))
    dim = 3 if info.get("measure", "volume") == "volume" else 2
    return total, dim


def _quantity_name(z: float) -> str:
    """Quantity of a probe-line point: letters, digits and underscores only (CF §2.3), e.g. ..._z12_5mm."""
    return f"stent_von_mises_z{z * 1e3:g}mm".replace(".", "_")


def quantity_values(ds: xr.Dataset, quantity: str) -> xr.DataArray:
    """Values (level) of one quantity of a GCI dataset, in its own units: variable value_<quantity>."""
    name = f"value_{quantity}"
    if name not in ds:
        raise KeyError(f"GCI dataset: no variable {name!r} for quantity {quantity!r}")
    return ds[name]


def extrapolated_values(ds: xr.Dataset) -> np.ndarray:
    """phi_ext21 of every quantity of a GCI dataset (variables extrapolated_value_<quantity>), in the order of
    the quantity axis, each in its quantity's units."""
    return np.array([float(ds[f"extrapolated_value_{q}"]) for q in ds["quantity"].values])


def gci_dataset(conv: xr.Dataset, points_z=DEFAULT_POINTS_Z, scalars=DEFAULT_SCALARS, measure: float | None = None,
                dim: int = 3, safety_factor: float = SAFETY_FACTOR, cfg: dict | None = None) -> xr.Dataset:
    """GCI of the mesh-convergence dataset (ureterfsi.analyses.aggregate.combine_levels) for the per-level scalars
    `scalars` (those present) and the stent probe-line von Mises stress at the axial positions points_z (m,
    linear interpolation along the line).

    The three finest levels (by cell count) enter; fewer than three levels is a ValueError. h = (measure /
    cells)^(1/dim): with measure None, h = cells^(-1/dim) (units "1"), enough because the mesh volume is the
    same on every level and only the ratios r21, r32 enter the GCI; with the mesh volume (mesh_measure of
    a sidecar), h is in m.

    Output: dims quantity (scalars, then the line points) and level (the input's levels, in its order);
    for each quantity q value_<q> (level) and extrapolated_value_<q> (scalar) in q's own units (CF: one unit per
    variable); cells and h (level), r21 and r32 (scalars), and along quantity the dimensionless apparent_order,
    e_a21, e_ext21, gci_fine21, gci32, asymptotic_ratio, convergence_ratio, diagnosis, note, and probe_z.
    Input attrs are kept (its provenance prefixed `input_`); the dataset's own provenance comes from
    provenance_attrs.
    """
    if "level" not in conv.dims:
        raise ValueError("not a mesh-convergence dataset: no `level` dimension")
    n_level = conv.sizes["level"]
    if n_level < 3:
        raise ValueError(f"the GCI needs three mesh levels (Celik et al. 2008), the dataset has {n_level}: "
                         f"{[str(v) for v in conv['level'].values]}")
    levels = [str(v) for v in conv["level"].values]
    cells = conv["cells"].values.astype(float)
    if not np.all(np.isfinite(cells) & (cells > 0)):
        raise ValueError(f"every level needs its cell count, got {cells.tolist()}")
    h = representative_cell_size(cells, 1.0 if measure is None else measure, dim)
    use = np.argsort(h, kind="stable")[:3]          # the three finest levels (smallest h)
    fine, medium, coarse = (levels[i] for i in use)

    names, units, long_names, values, probe_z = [], [], [], [], []
    for v in scalars:
        if v not in conv:
            continue
        names.append(v)
        units.append(conv[v].attrs.get("units", ""))
        long_names.append(conv[v].attrs.get("long_name", v))
        values.append(conv[v].values.astype(float))
        probe_z.append(np.nan)
    if points_z is not None and len(points_z):
        line = conv["stent_von_mises_line"]
        z = conv["z"].values.astype(float)
        for zp in points_z:
            zp = float(zp)
            if not z.min() - 1e-12 <= zp <= z.max() + 1e-12:
                raise ValueError(f"probe point z = {zp} m outside the probe line [{z.min()}, {z.max()}] m")
            names.append(_quantity_name(zp))
            line_units, line_name = cf_meta("stent_von_mises_line")
            units.append(line.attrs.get("units", line_units))
            long_names.append(at_z(line.attrs.get("long_name", line_name), zp))
            values.append(np.array([np.interp(zp, z, line.isel(level=i).values) for i in range(n_level)]))
            probe_z.append(zp)
    if not names:
        raise ValueError("no quantity for the GCI: none of the scalars is in the dataset and no probe point")

    results = [three_grid_gci(h[use], np.asarray(val)[use], safety_factor) for val in values]
    r0 = results[0]

    def per_q(attr):
        return np.array([getattr(r, attr) for r in results], dtype=float)

    meta = gci_variables(measure is None, fine, medium, coarse, DIAGNOSES)
    ds = xr.Dataset(
        {"cells": ("level", cells),
         "h": ("level", np.asarray(h, dtype=float)),
         "r21": ((), r0.r21), "r32": ((), r0.r32),
         "apparent_order": ("quantity", per_q("apparent_order")),
         "e_a21": ("quantity", per_q("e_a21")),
         "e_ext21": ("quantity", per_q("e_ext21")),
         "gci_fine21": ("quantity", per_q("gci_fine21")),
         "gci32": ("quantity", per_q("gci32")),
         "asymptotic_ratio": ("quantity", per_q("asymptotic_ratio")),
         "convergence_ratio": ("quantity", per_q("convergence_ratio")),
         "diagnosis": ("quantity", np.array([r.diagnosis for r in results], dtype=object)),
         "note": ("quantity", np.array([r.note for r in results], dtype=object)),
         "probe_z": ("quantity", np.array(probe_z, dtype=float))},
        coords={"quantity": ("quantity", np.array(names, dtype=object)),
                "level": ("level", np.array(levels, dtype=object))})
    attach(ds, meta)
    for q, u, ln, val, r in zip(names, units, long_names, values, results):
        qmeta = gci_quantity_variables(q, u, ln)
        ds[f"value_{q}"] = xr.DataArray(np.asarray(val), dims="level", attrs=cf_attrs(f"value_{q}", qmeta))
        ds[f"extrapolated_value_{q}"] = xr.DataArray(r.phi_ext21, attrs=cf_attrs(f"extrapolated_value_{q}", qmeta))

    attrs = {}
    for k, v in conv.attrs.items():
        if k in ("Conventions", "title"):
            continue
        if k in ("config_hash", "git_commit", "created") or k.startswith("version_"):
            k = f"input_{k}"
        attrs[k] = int(v) if isinstance(v, (bool, np.bool_)) else v
    extra = dict(method="three-grid Grid Convergence Index (Celik et al. 2008)", references=REFERENCE,
                 safety_factor=float(safety_factor), fine_level=fine, medium_level=medium, coarse_level=coarse,
                 gci_levels=",".join((fine, medium, coarse)), cell_size_dimension=int(dim))
    if measure is None:
        extra["cell_size_definition"] = ("h = N^(-1/d), i.e. (V/N)^(1/d) with V = 1: the mesh volume is the same "
                                         "on every level, so only the ratios r21, r32 matter")
    else:
        extra.update(mesh_measure=float(measure),
                     cell_size_definition="h = (V/N)^(1/d), V = mesh_measure (the same on every level)")
    attrs.update(provenance_attrs(cfg or {}, **extra))
    ds.attrs.update(attrs)
    ds.attrs["Conventions"] = "CF-1.8"
    ds.attrs["title"] = (f"ureterfsi mesh convergence GCI: model {conv.attrs.get('model', '?')}, "
                         f"levels {fine}/{medium}/{coarse}")
    return ds


# ---------------------------------------------------------------------------------------------- table
_DISPLAY = {"Pa": ("kPa", 1e-3), "m3 s-1": ("mm³/s", 1e9), "m": ("mm", 1e3), "m s-1": ("mm/s", 1e3)}
_LABELS = {"peak_outlet_flux": "peak outlet flow rate",
           "peak_stent_max_von_mises": "peak maximum stent von Mises stress",
           "peak_outlet_hole_flux": "peak flow rate through the outlet-most hole",
           "outlet_hole_peak_velocity": "peak hole-axis velocity across the outlet-most hole"}


def _g(x, digits=4) -> str:
    return "NaN" if not np.isfinite(x) else f"{x:.{digits}g}"


def _pct(x) -> str:
    return "NaN" if not np.isfinite(x) else f"{100 * x:.3g} %"


def gci_table(ds: xr.Dataset) -> list[dict]:
    """Rows (one per quantity) of the GCI table in the units of the dataset (SI); fractions as fractions."""
    fine, medium, coarse = ds.attrs["fine_level"], ds.attrs["medium_level"], ds.attrs["coarse_level"]
    rows = []
    for i, name in enumerate(ds["quantity"].values):
        d, val = ds.isel(quantity=i), quantity_values(ds, str(name))
        rows.append({
            "quantity": str(name), "units": str(val.attrs["units"]),
            f"phi1_{fine}": float(val.sel(level=fine)), f"phi2_{medium}": float(val.sel(level=medium)),
            f"phi3_{coarse}": float(val.sel(level=coarse)),
            "r21": float(ds["r21"]), "r32": float(ds["r32"]),
            "apparent_order": float(d["apparent_order"]),
            "phi_ext21": float(ds[f"extrapolated_value_{name}"]),
            "e_a21": float(d["e_a21"]), "e_ext21": float(d["e_ext21"]), "gci_fine21": float(d["gci_fine21"]),
            "gci32": float(d["gci32"]), "asymptotic_ratio": float(d["asymptotic_ratio"]),
            "diagnosis": str(d["diagnosis"].item()),
        })
    return rows


def write_gci_table(ds: xr.Dataset, csv_path=None, md_path=None) -> list[dict]:
    """The GCI table as CSV (SI units, full precision) and Markdown (kPa, mm³/s, percentages), atomically."""
    rows = gci_table(ds)
    header, md_rows, footer = None, None, ()
    if md_path:
        fine, medium, coarse = ds.attrs["fine_level"], ds.attrs["medium_level"], ds.attrs["coarse_level"]
        cells = {lv: int(ds["cells"].sel(level=lv)) for lv in (fine, medium, coarse)}
        head = ["Quantity", "Units", f"φ1 ({fine})", f"φ2 ({medium})", f"φ3 ({coarse})", "p", "φ_ext21",
                "e_a21", "e_ext21", "GCI_fine21", "GCI32", "GCI32/(r21^p GCI21)", "Convergence"]
        md_rows = []
        for i, r in enumerate(rows):
            unit, scale = _DISPLAY.get(r["units"], (r["units"], 1.0))
            z = float(ds["probe_z"].isel(quantity=i))
            label = (f"stent von Mises stress at z = {z * 1e3:g} mm" if np.isfinite(z)
                     else _LABELS.get(r["quantity"], r["quantity"].replace("_", " ")))
            phis = [r[k] for k in rows[0] if k.startswith("phi") and k != "phi_ext21"]
            md_rows.append(
                [label, unit] + [_g(v * scale) for v in phis]
                + [_g(r["apparent_order"], 3), _g(r["phi_ext21"] * scale), _pct(r["e_a21"]), _pct(r["e_ext21"]),
                   _pct(r["gci_fine21"]), _pct(r["gci32"]), _g(r["asymptotic_ratio"], 3), r["diagnosis"]])
        hs = ""
        if ds["h"].attrs.get("units") == "m":
            hs = ", ".join(f"{float(ds['h'].sel(level=lv)) * 1e3:.4g}" for lv in (fine, medium, coarse))
            hs = f"h = {hs} mm; "
        header = head
        footer = [f"Cells: {fine} {cells[fine]}, {medium} {cells[medium]}, {coarse} {cells[coarse]}; {hs}"
                  f"r21 = {float(ds['r21']):.4g}, r32 = {float(ds['r32']):.4g}; "
                  f"safety factor Fs = {ds.attrs['safety_factor']:g}."]
    write_table(rows, csv_path, md_path, header=header, md_rows=md_rows, footer=footer)
    return rows
