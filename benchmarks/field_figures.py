"""Cost of the field figures' sampling (ureterfsi.plotting.fields) on the default configuration's field model:
the model-3 coarse quarter mesh of config/config.yaml, its urine cells, synthetic nodal values (the cost does
not depend on the values), the four instants of Figs. 6-9. Numbers: docs/fields.md.

    .venv/bin/python benchmarks/field_figures.py [--work DIR]
"""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

import numpy as np  # noqa: E402

from ureterfsi.mesh import tags  # noqa: E402
from ureterfsi.config import load_config  # noqa: E402
from ureterfsi.mesh.geometry import UreterGeometry  # noqa: E402
from ureterfsi.mesh.build import build_mesh  # noqa: E402
from ureterfsi.mesh.io import read_msh  # noqa: E402
from ureterfsi.data.fieldfiles import FieldSet, hole_flow_section, pressure_lines  # noqa: E402


def urine_tets(msh: Path) -> tuple[np.ndarray, np.ndarray]:
    """(vertex coordinates, urine tetrahedra as vertex indices) of a gmsh mesh."""
    m = read_msh(msh)
    return m.coords, m.elements(3, tags.FLUID)


class SyntheticFields(FieldSet):
    """A FieldSet on given vertices and cells whose every quantity is fixed random nodal values."""

    def values(self, quantity, time):
        n = len(self.points)
        return {"pressure": np.ones((n, 1)), "displacement": np.zeros((n, 3))}.get(
            quantity, np.random.default_rng(0).normal(size=(n, 3)))


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--work", type=Path, default=ROOT / "results" / "benchmarks" / "field_figures")
    args = ap.parse_args()
    cfg = load_config(ROOT / "config" / "config.yaml")
    args.work.mkdir(parents=True, exist_ok=True)
    msh = args.work / "model3_coarse.msh"
    if not msh.exists():
        build_mesh(cfg, "3", "coarse", "quarter", msh, msh.with_suffix(".json"))
    points, cells = urine_tets(msh)
    times = [float(t) for t in cfg["figures"]["hole_velocity_times"]]
    fs = SyntheticFields(args.work, points, cells, np.array(sorted(set(times))), [{}], {})
    g = UreterGeometry.from_config(cfg)
    hole_z = g.length - g.hole_end_clearance
    tic = time.perf_counter()
    sec = hole_flow_section(fs, times, hole_z, g)
    t_sec = time.perf_counter() - tic
    tic = time.perf_counter()
    pressure_lines(fs, [float(t) for t in cfg["figures"]["wave_times"]], g)
    t_lines = time.perf_counter() - tic
    print(f"urine cells {len(cells)}, vertices {len(points)}")
    print(f"hole section, {len(times)} instants x {sec.y.size * sec.z.size} points: {t_sec:.2f} s")
    print(f"pressure lines, {len(cfg['figures']['wave_times'])} instants x 2 lines x 300 points: {t_lines:.2f} s")


if __name__ == "__main__":
    main()
