"""Reading the run's field files (ureterfsi.fields: XDMF 3 + HDF5) without dolfinx, for figures and checks.

HDF5 is read through netCDF4 (HDF5 files are netCDF-4 readable), so no second HDF5 binding is loaded.
"""
from __future__ import annotations

import json
import xml.etree.ElementTree as ET
from dataclasses import dataclass
from pathlib import Path

import netCDF4
import numpy as np


def _read(directory: Path, item: str) -> np.ndarray:
    """Array of an XDMF HDF DataItem text 'file.h5:/group/.../name'."""
    fname, path = item.strip().split(":", 1)
    *groups, name = path.strip("/").split("/")
    with netCDF4.Dataset(directory / fname) as ds:
        node = ds
        for g in groups:
            node = node.groups[g]
        return np.asarray(node.variables[name][:])


@dataclass
class FieldSet:
    """One part of a run's field output: reference vertex coordinates (m), cells, snapshot times (s) and
    the data item of each (time, quantity)."""
    directory: Path
    points: np.ndarray
    cells: np.ndarray
    times: np.ndarray
    items: list
    units: dict

    def values(self, quantity: str, time: float) -> np.ndarray:
        """Values (vertices or cells, components) of a quantity at the snapshot time nearest to `time`, which
        must be a snapshot time within 1e-9 s."""
        k = int(np.argmin(np.abs(self.times - time)))
        if abs(self.times[k] - time) > 1e-9:
            raise KeyError(f"{self.directory}: no snapshot at t = {time:g} s (times {self.times.tolist()})")
        if quantity not in self.items[k]:
            raise KeyError(f"{self.directory}: no quantity {quantity!r} (has {sorted(self.items[k])})")
        return _read(self.directory, self.items[k][quantity])


def read_fields(directory, part: str) -> FieldSet:
    """The part's FieldSet from <directory>/<part>.xdmf and fields.json."""
    directory = Path(directory)
    index = directory / f"{part}.xdmf"
    if not index.exists():
        raise FileNotFoundError(f"{index}: no field file of part {part!r}")
    root = ET.parse(index).getroot()
    grids = [g for g in root.iter("Grid") if g.get("GridType") == "Uniform"]
    topo = _read(directory, grids[0].find("Topology/DataItem").text)
    geom = _read(directory, grids[0].find("Geometry/DataItem").text)
    times = np.array([float(g.find("Time").get("Value")) for g in grids])
    items = [{a.get("Name"): a.find("DataItem").text for a in g.findall("Attribute")} for g in grids]
    units = json.loads((directory / "fields.json").read_text())["units"]
    return FieldSet(directory, geom, topo.astype(np.int64), times, items, units)
