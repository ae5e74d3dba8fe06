"""ureterfsi.fsi.progress on synthetic step-time sequences: the ETA against the true remaining wall time."""
import math
from collections import namedtuple

import pytest

from ureterfsi.fsi.progress import Progress, format_seconds


Snap = namedtuple("Snap", "eta total_steps fraction describe step")


def _replay(walls, dts, end=None):
    """Feed steps of wall time walls[i] and length dts[i]; yield (state after the step, true remaining wall,
    old ETA), the state as (eta, total_steps, fraction, describe())."""
    end = sum(dts) if end is None else end
    p, t, clock = Progress(0.0, end, 0.0), 0.0, 0.0
    for k, (w, dt) in enumerate(zip(walls, dts)):
        t, clock = t + dt, clock + w
        p.update(k + 1, t, dt, dts[k + 1] if k + 1 < len(dts) else dt, clock)
        old = clock * (1 - t / end) / (t / end)            # the cumulative average this replaces
        yield Snap(p.eta, p.total_steps, p.fraction, p.describe(), p.step), sum(walls[k + 1:]), old


def test_slow_first_step_is_left_out():
    walls, dts = [600.0] + [2.0] * 299, [0.01] * 300       # compile + factorise, then 2 s per step
    out = list(_replay(walls, dts))
    assert out[0][0].eta is None and "ETA unknown" in out[0][0].describe
    p, truth, old = out[2]
    assert p.eta == pytest.approx(truth, rel=0.2) and old > 10 * truth
    assert p.describe.startswith("step 3 of ~300 (1.0 %)")


def test_slowdown_is_followed_within_a_window():
    walls, dts = [30.0] + [1.0] * 99 + [3.0] * 200, [0.01] * 300
    out = list(_replay(walls, dts))
    p, truth, old = out[99 + 10]                          # 10 steps into the slowdown
    assert p.eta == pytest.approx(truth, rel=0.2)
    assert abs(old - truth) > 0.3 * truth


def test_dt_halvings_change_n_and_the_rate():
    # 50 steps of 0.02 s, then the step is halved for good (same wall per step): the rest takes twice the steps
    dts = [0.02] * 50 + [0.01] * 100
    walls = [20.0] + [1.0] * 149
    out = list(_replay(walls, dts))
    p, truth, _ = out[49]
    assert p.total_steps == 50 + math.ceil(1.0 / 0.01 - 1e-9)      # the next step is 0.01 s: 150 in all
    p, truth, _ = out[65]
    assert p.eta == pytest.approx(truth, rel=0.2)
    assert p.total_steps == 150 and p.fraction == pytest.approx(sum(dts[:66]) / 2.0)
    last = out[-1][0]
    assert last.eta == 0.0 and last.total_steps == last.step == 150 and last.fraction == 1.0


def test_bad_interval_and_format():
    with pytest.raises(ValueError, match="t_end > t_start"):
        Progress(1.0, 1.0, 0.0)
    assert format_seconds(3725.4) == "1:02:05"


COMPILE_SCRIPT = """
import logging, sys, uuid
logging.basicConfig(level=logging.INFO, format="%(levelname)s:%(name)s:%(message)s")   # as the workflow scripts
import ureterfsi.fsi  # noqa: F401
from ureterfsi.study.cli import configure_logging
configure_logging(sys.stderr)
if sys.argv[1] == "debug":
    logging.getLogger("distutils").setLevel(logging.DEBUG)
from mpi4py import MPI
import ufl
from dolfinx import fem, mesh
msh = mesh.create_unit_interval(MPI.COMM_WORLD, 2)
fem.form(float(uuid.uuid4().int % 10**9 + 1) * ufl.dx(msh))             # a new form: compiled now
logging.getLogger("ureterfsi.fsi").info("solve done")
"""


@pytest.mark.parametrize("level", ["info", "debug"])
def test_form_compilation_leaves_no_lines_in_the_log(repo_root, level):
    """A log of a process that compiles a form (root at INFO, as the workflow scripts set it) has no
    compiler lines; with the logger "distutils" at DEBUG they are there (the test can see them)."""
    import subprocess
    import sys

    out = subprocess.run([sys.executable, "-c", COMPILE_SCRIPT, level], cwd=repo_root, capture_output=True,
                         text=True, timeout=300)
    assert out.returncode == 0, out.stderr
    log = out.stdout + out.stderr
    assert "solve done" in log
    compiler = [ln for ln in log.splitlines() if "gcc" in ln or "build_ext" in ln or "building '" in ln]
    assert (compiler == []) if level == "info" else len(compiler) >= 3, log
