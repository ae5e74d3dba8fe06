"""Metadata of every dataset the project writes, the one registry's public path: the tables of variables (UDUNITS
units, long_name, CF standard_name) of the run and study files (VARIABLES) and of the field files, the wall motion,
the design parameters, the GCI and the ladder (each in its own words, templated entries built by a function; kept in
ureterfsi.data.cf_tables and re-exported here), and the functions that apply them: cf_meta and cf_attrs, attach and
annotate, the netCDF encoding CF 1.8 accepts, the global attributes, and the atomic netCDF write.

Imports no dolfinx, PETSc or MPI: post-processing and figures use it without the solver stack.
CF 1.8: coordinate variables carry no `_FillValue` (§2.5.1); integers are written as int32 (§2.2 has no
int64 in the classic data types the checkers accept); the `time` axis is a CF time coordinate (§4.4):
standard_name "time", units "s since <EPOCH>" and a calendar, the epoch standing for the start of the run
(t = 0). Readers open with decode_times=False (ureterfsi.data.checked.open_netcdf), so time stays in seconds.
Dimensions are in the order CF §2.4 recommends, `time` right of every other dimension: the producers build
their arrays so and write_netcdf refuses any other order.
"""
from __future__ import annotations

import shlex
import sys
from datetime import datetime, timezone
from importlib.metadata import version

import numpy as np

from ureterfsi.data.provenance import atomic_path
from ureterfsi.data.cf_tables import (DESIGN_PARAMETERS, FIELD_VARIABLES, GCI_VARIABLES, LADDER_VARIABLES,
                                     RUNG_CHECK_VARIABLES, STANDARD_NAMES, VARIABLES, WALL_MOTION_VARIABLES, at_time,
                                     at_z, gci_quantity_variables, gci_variables, ladder_variables,
                                     reference_metadata, rung_check_metadata)

CONVENTIONS = "CF-1.8"
INSTITUTION = "ureterfsi project (open reproduction)"
SOURCE = "ureterfsi: monolithic ALE fluid-structure interaction with FEniCSx (dolfinx 0.5)"
REFERENCES = ("Numerical study of fully coupled fluid-structure interaction of stented ureter by varying the "
              "stent side-holes (the study reproduced; text in shared/paper/stented-ureter-fsi.txt)")

# the registry's tables (cf_tables) are part of this module's interface: ureterfsi.data.cf is the one path
__all__ = [
    "CALENDAR", "CONVENTIONS", "DESIGN_PARAMETERS", "FIELD_VARIABLES", "GCI_VARIABLES", "INSTITUTION",
    "LADDER_VARIABLES", "REFERENCES", "RUNG_CHECK_VARIABLES", "SOURCE", "STANDARD_NAMES", "VARIABLES",
    "WALL_MOTION_VARIABLES", "annotate", "at_time", "at_z", "attach", "cf_attrs", "cf_meta",
    "check_dimension_order", "encoding", "gci_quantity_variables", "gci_variables", "global_attrs", "history_entry",
    "ladder_variables", "reference_metadata", "rung_check_metadata", "snakemake_version", "standard_names",
    "write_netcdf",
]

# calendar of the time coordinate (CF §4.4.1); its epoch in VARIABLES["time"] is a stand-in for t = 0
CALENDAR = "proleptic_gregorian"


def cf_meta(name: str, table: dict | None = None) -> tuple[str, str]:
    """(units, long_name) of a variable of `table` (default VARIABLES); KeyError naming it otherwise."""
    try:
        return (VARIABLES if table is None else table)[name]
    except KeyError:
        where = " (ureterfsi.data.cf.VARIABLES)" if table is None else ""
        raise KeyError(f"no CF metadata for variable {name!r}{where}") from None


def cf_attrs(name: str, table: dict | None = None) -> dict:
    """{"units", "long_name"} of a variable of `table` (default VARIABLES), as attributes."""
    units, long_name = cf_meta(name, table)
    return {"units": units, "long_name": long_name}


def attach(ds, table: dict | None = None):
    """Set units and long_name of every variable of `ds` from `table` (default VARIABLES); returns ds."""
    table = VARIABLES if table is None else table
    for name in list(ds.variables):
        try:
            units, long_name = table[str(name)]
        except KeyError:
            raise KeyError(f"no CF metadata for variable {name!r}") from None
        ds[name].attrs.update(units=units, long_name=long_name)
    return ds


def annotate(ds, table: dict | None = None):
    """attach(ds, table), and the CF standard_name where one exists; returns ds."""
    return standard_names(attach(ds, table))


def standard_names(ds):
    """Add the CF standard_name of the variables that have one (STANDARD_NAMES), and the time coordinate's
    units and calendar (CF §4.4: "<unit> since <epoch>"); returns ds."""
    for name, sn in STANDARD_NAMES.items():
        if name in ds.variables:
            ds[name].attrs["standard_name"] = sn
    if "time" in ds.variables:
        ds["time"].attrs.update(units=VARIABLES["time"][0], calendar=CALENDAR)
    return ds


def history_entry(argv=None) -> str:
    """'<ISO UTC time>: <command line>' (CF §2.6.2 history)."""
    cmd = " ".join(shlex.quote(a) for a in (sys.argv if argv is None else argv))
    return f"{datetime.now(timezone.utc).isoformat(timespec='seconds')}: {cmd}"


def snakemake_version() -> str | None:
    """Version of Snakemake when this process runs under it (a job script or a run: block), else None."""
    if "snakemake" not in sys.modules:
        return None
    try:
        return version("snakemake")
    except Exception:  # snakemake not installed in this interpreter
        return None


def global_attrs(title: str) -> dict:
    """CF global attributes: Conventions, title, institution, source, history, references, and the
    Snakemake version when run under Snakemake."""
    attrs = {"Conventions": CONVENTIONS, "title": title, "institution": INSTITUTION, "source": SOURCE,
             "history": history_entry(), "references": REFERENCES}
    sm = snakemake_version()
    if sm:
        attrs["snakemake_version"] = sm
    return attrs


def encoding(ds) -> dict:
    """netCDF encoding CF 1.8 checkers accept: no _FillValue on coordinate variables (and on variables
    without missing values), int32 for 64-bit integers."""
    enc = {}
    for name, var in ds.variables.items():
        e = {}
        kind = var.dtype.kind
        if name in ds.coords or kind not in "fc":
            e["_FillValue"] = None
        if kind in "iu" and var.dtype.itemsize == 8:
            info = np.iinfo(np.int32)
            vals = np.asarray(var.values)
            if vals.size and (vals.min() < info.min or vals.max() > info.max):
                raise ValueError(f"variable {name!r} does not fit int32 (CF 1.8 netCDF classic data types)")
            e["dtype"] = "int32"
        enc[name] = e
    return enc


def check_dimension_order(ds) -> None:
    """Refuse a variable whose `time` dimension is not its last (CF §2.4: dimensions that are not T, Z, Y or X,
    here indices such as `hole` or `model`, lie left of them): producers build time-last arrays."""
    for name, var in ds.variables.items():
        if "time" in var.dims and var.dims[-1] != "time":
            raise ValueError(f"variable {name!r} has dimensions {var.dims}: CF §2.4 wants `time` last")


def write_netcdf(ds, path, title: str | None = None) -> None:
    """Write `ds` as CF-1.8 netCDF atomically: global attributes (global_attrs; the dataset's own
    title unless `title` is given) and the CF encoding; a variable not in the CF dimension order is refused
    (check_dimension_order)."""
    check_dimension_order(ds)
    ds = ds.copy()
    ds.attrs.update(global_attrs(title or str(ds.attrs.get("title", "ureterfsi dataset"))))
    standard_names(ds)
    with atomic_path(path) as tmp:
        ds.to_netcdf(tmp, encoding=encoding(ds))
