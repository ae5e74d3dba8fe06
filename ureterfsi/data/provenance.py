"""Provenance attributes and atomic file output.

Every file under results/ is written to a temporary sibling and renamed into place, so an interrupted
or failed job never leaves a partial file where a complete one is expected.
"""
from __future__ import annotations

import contextlib
import hashlib
import importlib
import json
import os
import subprocess
import secrets
from datetime import datetime, timezone
from importlib import metadata
from pathlib import Path

from ureterfsi import REPO_ROOT

# Generation of the layout of every file ureterfsi writes (attribute FORMAT_VERSION_ATTR, set by
# provenance_attrs); readers (ureterfsi.data.checked) refuse another one. Raise it when a reader would
# misread an older file.
FORMAT_VERSION = 1
FORMAT_VERSION_ATTR = "ureterfsi_format_version"


def config_hash(cfg: dict) -> str:
    """SHA-256 (first 16 hex digits) of the canonical JSON form of a configuration."""
    text = json.dumps(cfg, sort_keys=True, separators=(",", ":"), default=str)
    return hashlib.sha256(text.encode()).hexdigest()[:16]


def git_commit() -> str:
    """Commit of the source tree ('+dirty' if it has uncommitted changes), or 'unknown'."""
    try:
        rev = subprocess.run(["git", "rev-parse", "HEAD"], cwd=REPO_ROOT, capture_output=True,
                             text=True, check=True).stdout.strip()
        dirty = subprocess.run(["git", "status", "--porcelain", "--untracked-files=no"], cwd=REPO_ROOT,
                               capture_output=True, text=True, check=True).stdout.strip()
        return rev + ("+dirty" if dirty else "")
    except (OSError, subprocess.CalledProcessError):
        return "unknown"


def package_versions() -> dict:
    """Versions of the numerical stack that produced a result."""
    out = {}
    for name in ("ureterfsi", "dolfinx", "ufl", "ffcx", "petsc4py", "gmsh", "numpy", "xarray"):
        try:
            out[name] = str(importlib.import_module(name).__version__)
        except Exception:  # a missing optional package is recorded as such
            out[name] = "not installed"
    try:        # the workflow engine, from its distribution record (importing it costs ~1 s)
        out["snakemake"] = metadata.version("snakemake")
    except metadata.PackageNotFoundError:
        out["snakemake"] = "not installed"
    return out


def provenance_attrs(cfg: dict, **extra) -> dict:
    """Flat, netCDF-safe provenance attributes: config hash, git commit, versions, creation time, file format."""
    attrs = {
        "config_hash": config_hash(cfg),
        "git_commit": git_commit(),
        "created": datetime.now(timezone.utc).isoformat(timespec="seconds"),
        FORMAT_VERSION_ATTR: FORMAT_VERSION,
    }
    attrs.update({f"version_{k}": v for k, v in package_versions().items()})
    attrs.update({k: (v if isinstance(v, (int, float, str)) else json.dumps(v)) for k, v in extra.items()})
    return attrs


@contextlib.contextmanager
def atomic_path(path: str | os.PathLike):
    """Yield a temporary path next to `path`; rename it onto `path` only if the block succeeds. The file is
    created with mode 0666 for the kernel to apply the umask, as a plain open() does (mkstemp's is 0600)."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    while True:
        tmp = path.parent / f".{path.stem}.{secrets.token_hex(4)}{path.suffix}.part"
        try:
            os.close(os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o666))
            break
        except FileExistsError:
            continue
    try:
        yield tmp
        os.replace(tmp, path)
    finally:
        if os.path.exists(tmp):
            os.remove(tmp)


def write_json(path: str | os.PathLike, data: dict) -> None:
    """Write `data` as indented JSON, atomically."""
    with atomic_path(path) as tmp:
        tmp.write_text(json.dumps(data, indent=2, sort_keys=True, default=float) + "\n")
