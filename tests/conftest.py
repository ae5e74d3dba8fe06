"""Shared fixtures: the repository root and a fresh, validated copy of the default configuration."""
from __future__ import annotations

import copy
import gc
from pathlib import Path  # noqa: F401

import pytest

from ureterfsi import REPO_ROOT   # importing ureterfsi loads netCDF4 before any test imports dolfinx
from ureterfsi.config import load_config


@pytest.fixture(autouse=True, scope="module")
def _collect_solvers():
    """Collect each test module's garbage when it ends: problems hold PETSc matrices and MUMPS factors in
    reference cycles (weakref finalizers, UFL forms) that Python's own collector, blind to their size, keeps
    for long (the suite's process reached 13 GB without it)."""
    yield
    gc.collect()


@pytest.fixture(scope="session")
def repo_root() -> Path:
    return REPO_ROOT


@pytest.fixture(scope="session")
def _default_cfg() -> dict:
    return load_config(REPO_ROOT / "config" / "config.yaml")


@pytest.fixture
def cfg(_default_cfg) -> dict:
    """A deep copy of the validated default config (config/config.yaml); safe to modify."""
    return copy.deepcopy(_default_cfg)
