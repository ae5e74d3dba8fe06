"""The fully coupled rung: wall, urine and stent in one monolithic ALE Newton system (paper §2)."""
from __future__ import annotations

from dataclasses import replace
from functools import partial

import xarray as xr

from ureterfsi.study.fields import coupled_parts
from ..fsi.problem import MonolithicFSI
from ureterfsi.mesh.geometry import StentModel
from ..scenes.ureter import ureter_scene
from . import pipeline
from .options import RunSpec, solver_options
from .probes import UreterProbes


def pose(cfg: dict, spec: RunSpec, settings, mesh, cell_tags, facet_tags) -> pipeline.Posed:
    """The ureter scene of model `spec.model` on the run's mesh and its probes, stress read from the coupled state."""
    scene = ureter_scene(cfg, mesh, cell_tags, facet_tags, axisymmetric=spec.symmetry == "axisymmetric")
    options = replace(solver_options(cfg, fully_coupled=True), mumps_out_of_core=spec.out_of_core)
    pb = MonolithicFSI(scene, options)
    obs = UreterProbes(pb, cfg, StentModel.from_config(cfg, spec.model), spec.symmetry, cfg["time"]["probe_times"])
    stent, surface = (obs.stent, obs.surface) if obs.has_stent else (None, None)
    return pipeline.Posed(
        pb, obs, lambda q: coupled_parts(pb, stent, q, cfg["fluid"]["reference_pressure"], surface),
        solver=f"monolithic ALE, P2-P2-P1-P0, BDF2, {pb.options.coupled_solution()}")


def run(cfg: dict, spec: RunSpec, out_path: str, checkpoint_path: str | None = None) -> xr.Dataset:
    """Fully coupled solve of one model on one mesh; writes the probe dataset atomically."""
    return pipeline.run(cfg, spec, out_path, checkpoint_path, "fully_coupled", partial(pose, cfg, spec))
