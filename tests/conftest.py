"""Shared fixtures: the repository root and a fresh, validated copy of the default configuration."""
from __future__ import annotations

import copy
import ctypes
import gc
import time
from pathlib import Path

import pytest

from ureterfsi import REPO_ROOT   # importing ureterfsi loads netCDF4 before any test imports dolfinx
from ureterfsi.config import load_config

LIBC = ctypes.CDLL(None)     # this process's C library (glibc)


def _rss_bytes() -> tuple[int, int]:
    """Current and peak resident set size of this process (VmRSS, VmHWM of /proc/self/status), bytes."""
    fields = {}
    with open("/proc/self/status") as status:
        for line in status:
            if line.startswith(("VmRSS:", "VmHWM:")):
                name, kib, _ = line.split()
                fields[name] = int(kib) * 1024
    return fields["VmRSS:"], fields["VmHWM:"]


def pytest_addoption(parser):
    parser.addoption("--rss-log", metavar="PATH", default=None,
                     help="write the resident memory of the pytest process before and after each test, and its "
                          "growth per test module, to PATH (tab-separated; how docs/performance.md's memory "
                          "table is measured)")


class _RSSLog:
    """Per-test RSS rows and a per-module summary (growth = RSS after the module's last test minus before its
    first; peak = the process's high-water mark at the module's end)."""

    def __init__(self, path: Path):
        self.path = path
        self.stream = path.open("w")
        self.stream.write("test\trss_before_MiB\trss_after_MiB\tgrowth_MiB\tpeak_MiB\tseconds\n")
        self.modules: dict[str, list[float]] = {}
        self.trimmed: dict[str, float] = {}      # {module: MiB malloc_trim gave back at its end}

    @pytest.hookimpl(hookwrapper=True)
    def pytest_runtest_protocol(self, item, nextitem):
        before, _ = _rss_bytes()
        start = time.perf_counter()
        yield
        after, peak = _rss_bytes()
        seconds = time.perf_counter() - start
        mib = 1024 ** 2
        self.stream.write(f"{item.nodeid}\t{before / mib:.0f}\t{after / mib:.0f}\t{(after - before) / mib:.0f}"
                          f"\t{peak / mib:.0f}\t{seconds:.1f}\n")
        self.stream.flush()
        module = self.modules.setdefault(item.location[0], [before / mib, after / mib, peak / mib, 0.0])
        module[1:] = [after / mib, peak / mib, module[3] + seconds]

    def pytest_sessionfinish(self):
        self.stream.write("\nmodule\trss_before_MiB\trss_after_MiB\tgrowth_MiB\tpeak_MiB\tseconds\ttrimmed_MiB\n")
        for name, (before, after, peak, seconds) in self.modules.items():
            self.stream.write(f"{name}\t{before:.0f}\t{after:.0f}\t{after - before:.0f}\t{peak:.0f}"
                              f"\t{seconds:.0f}\t{self.trimmed.get(name, 0.0):.0f}\n")
        self.stream.close()


def pytest_configure(config):
    path = config.getoption("--rss-log")
    if path:
        config.pluginmanager.register(_RSSLog(Path(path)), "rss-log")


@pytest.fixture(autouse=True, scope="module")
def _collect_solvers(request):
    """Collect each test module's garbage when it ends (problems of the partitioned scheme are reference cycles,
    closed when collected: fsi.release) and give the heap's free pages back to the system (glibc's malloc_trim);
    the memory given back is logged with --rss-log."""
    yield
    gc.collect()
    before = _rss_bytes()[0]
    LIBC.malloc_trim(0)
    log = request.config.pluginmanager.get_plugin("rss-log")
    if log is not None:
        log.trimmed[request.node.nodeid] = (before - _rss_bytes()[0]) / 1024 ** 2


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
