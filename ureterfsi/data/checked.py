"""Checked readers of the files the pipeline makes: netCDF datasets, JSON sidecars, gmsh meshes.

Each reader checks what it reads and raises BadFile, whose message is one line `<path>: <what is wrong>`
(missing, empty, truncated, not netCDF, written by an incompatible file-format version, missing
attribute or variable). A file's contract (Contract) lives next to its writer.
"""
from __future__ import annotations

import hashlib
import json
from dataclasses import dataclass, field
from pathlib import Path

import xarray as xr

from ureterfsi.data.cf import VARIABLES
from ureterfsi.data.provenance import FORMAT_VERSION, FORMAT_VERSION_ATTR

_NETCDF_MAGIC = (b"\x89HDF\r\n\x1a\n", b"CDF\x01", b"CDF\x02", b"CDF\x05")


class BadFile(ValueError):
    """A pipeline file that cannot be used; ``str`` is one line: `<path>: <what is wrong>`."""

    def __init__(self, path, what: str):
        self.path, self.what = str(path), " ".join(str(what).split())
        super().__init__(f"{self.path}: {self.what}")

    def __reduce__(self):      # picklable (MPI broadcast of a reading error)
        return BadFile, (self.path, self.what)


@dataclass(frozen=True)
class Contract:
    """What a reader relies on in a file: its kind (for messages), attributes and variables, and the table of
    units its writer attaches (ureterfsi.data.cf: name -> (units, long_name)); every variable of `variables`
    that the table names must carry those units (a run file converted to ml/s or ms is refused)."""
    kind: str
    attrs: tuple = ()
    variables: tuple = ()
    units: dict | None = field(default=None, hash=False, compare=False)
    versioned: bool = True     # carries the file-format version (provenance_attrs); fields.json does not


# what the readers of a mesh's JSON sidecar (ureterfsi.mesh.build.build_mesh) rely on
MESH_SIDECAR = Contract("mesh sidecar", attrs=("model", "level", "symmetry", "cells", "cells_total", "measure",
                                               "subdomain_measure", "hole_pair_z"))


def _check_exists(path: Path, kind: str) -> None:
    if not path.exists():
        raise BadFile(path, f"no such {kind}")
    if path.is_dir():
        raise BadFile(path, f"is a directory, not a {kind}")
    if path.stat().st_size == 0:
        raise BadFile(path, f"empty {kind} (0 bytes)")


def _check_version(path, version, kind: str, written_by=None) -> None:
    """The file-format version recorded by provenance_attrs must be the one this code reads."""
    if version is None:
        raise BadFile(path, f"{kind} without attribute '{FORMAT_VERSION_ATTR}': written by an older or foreign "
                            f"program (this ureterfsi reads format {FORMAT_VERSION}); re-run the rule that makes it")
    try:
        ok = int(version) == FORMAT_VERSION
    except (TypeError, ValueError):
        ok = False
    if not ok:
        by = f" by ureterfsi {written_by}" if written_by else ""
        raise BadFile(path, f"{kind} written{by} in file format {version!r}, this ureterfsi reads format "
                            f"{FORMAT_VERSION}; re-run the rule that makes it")


def open_netcdf(path, contract: Contract) -> xr.Dataset:
    """The dataset at `path`, loaded into memory (the file is closed), checked against `contract`. Times are
    not decoded: `time` (units "s since <epoch>", ureterfsi.data.cf) stays in seconds from the run's start."""
    path = Path(path)
    _check_exists(path, contract.kind)
    with open(path, "rb") as fh:
        head = fh.read(8)
    if not head.startswith(_NETCDF_MAGIC):
        raise BadFile(path, f"not a netCDF file (starts with {head[:8]!r}), expected a {contract.kind}")
    try:
        with xr.open_dataset(path, decode_times=False) as ds:
            ds = ds.load()
    except Exception as err:  # netCDF4/HDF5 report truncation as OSError, RuntimeError or KeyError
        raise BadFile(path, f"truncated or corrupt netCDF ({type(err).__name__}: {err})") from None
    _check_version(path, ds.attrs.get(FORMAT_VERSION_ATTR), contract.kind, ds.attrs.get("version_ureterfsi"))
    for key in contract.attrs:
        if key not in ds.attrs:
            raise BadFile(path, f"missing attribute '{key}' of a {contract.kind}")
    for name in contract.variables:
        if name not in ds.variables:
            raise BadFile(path, f"missing variable '{name}' of a {contract.kind}")
        if contract.units and name in contract.units:
            # every time coordinate carries the CF units of VARIABLES["time"] (metadata.standard_names)
            want = VARIABLES["time"][0] if name == "time" else contract.units[name][0]
            got = ds[name].attrs.get("units")
            if got != want:
                raise BadFile(path, f"variable '{name}' of a {contract.kind} in units {got!r}, expected {want!r} "
                                    f"(converted or written by another program?)")
    ds.encoding["source"] = str(path)
    return ds


def read_json(path, contract: Contract) -> dict:
    """A JSON object written by ureterfsi (e.g. a mesh sidecar), checked against `contract` (attrs = keys)."""
    path = Path(path)
    _check_exists(path, contract.kind)
    try:
        data = json.loads(path.read_text())
    except UnicodeDecodeError:
        raise BadFile(path, f"not a text file, expected a {contract.kind} (JSON)") from None
    except json.JSONDecodeError as err:
        raise BadFile(path, f"not valid JSON (line {err.lineno} column {err.colno}: {err.msg}); truncated?") from None
    if not isinstance(data, dict):
        raise BadFile(path, f"a JSON {type(data).__name__}, expected the object of a {contract.kind}")
    if contract.versioned:
        _check_version(path, data.get(FORMAT_VERSION_ATTR), contract.kind, data.get("version_ureterfsi"))
    for key in contract.attrs:
        if key not in data:
            raise BadFile(path, f"missing key '{key}' of a {contract.kind}")
    return data


def check_msh(path) -> None:
    """Cheap checks of a gmsh .msh 4.1 ASCII file before gmsh reads it: present, not empty, starts with
    $MeshFormat 4.1 and ends with a closing section tag (a truncated file does not)."""
    path = Path(path)
    _check_exists(path, "gmsh mesh")
    with open(path, "rb") as fh:
        head = fh.read(64)
        fh.seek(max(0, path.stat().st_size - 64))
        tail = fh.read()
    lines = head.split(b"\n")
    if lines[0].strip() != b"$MeshFormat":
        raise BadFile(path, f"not a gmsh mesh (first line {lines[0][:40]!r}, expected '$MeshFormat')")
    version = lines[1].split()[0] if len(lines) > 1 and lines[1].split() else b"?"
    if not version.startswith(b"4"):
        raise BadFile(path, f"gmsh mesh format {version.decode(errors='replace')}, expected 4.1 (ureterfsi.mesh.build)")
    last = tail.rstrip().rsplit(b"\n", 1)[-1].strip()
    if not last.startswith(b"$End"):
        raise BadFile(path, "truncated gmsh mesh (does not end with a closing '$End...' section tag)")


def gmsh_error(path, err: Exception) -> BadFile:
    """The one-line BadFile of an exception that gmsh raised while reading `path`."""
    return BadFile(path, f"gmsh cannot read this mesh ({err})")


def sha256_file(path, chunk: int = 1 << 20, kind: str = "file") -> str:
    """SHA-256 (hex) of a file's content; BadFile if it is missing, a directory or empty."""
    _check_exists(Path(path), kind)
    h = hashlib.sha256()
    with open(path, "rb") as fh:
        for block in iter(lambda: fh.read(chunk), b""):
            h.update(block)
    return h.hexdigest()


# what the readers of a run file (ureterfsi.analyses.aggregate, ureterfsi.analyses.ladder) rely on; the stent variables
# exist only in stented runs
RUN_FILE = Contract("run file", attrs=("model", "mesh_level", "symmetry", "fidelity", "wall_time_s"),
                    variables=("time", "z", "probe_time", "outlet_flux", "inlet_flux", "outlet_mean_axial_velocity",
                               "fluid_volume", "max_wall_displacement", "pulse_centre", "wall_radial_displacement",
                               "step_time", "step_dt", "newton_iterations"), units=VARIABLES)
