"""The run sequence every rung of the fidelity ladder shares: mesh read, the rung's problem and probes posed on
it, counts and progress lines, checkpoints bound to the run's identity, integration from rest, field output,
the probe dataset with its provenance attributes, atomic write. A rung passes in what is its own (`Posed`)."""
from __future__ import annotations

import logging
import resource
import time as _time
from dataclasses import dataclass, field
from typing import Callable

import xarray as xr
from mpi4py import MPI

from ureterfsi.study.fields import field_writer
from ..fsi import TimeIntegrator, TimeSettings
from ..fsi.problem import MonolithicFSI
from ..fsi.release import destroy_held
from ureterfsi.mesh.io import load_mesh
from ureterfsi.data.cf import write_netcdf
from .options import RunSpec, time_settings
from .end_probes import ends_probes
from .probes import UreterProbes, probes_dataset

log = logging.getLogger("ureterfsi.study")


@dataclass
class Posed:
    """A rung's problem on the run's mesh: what the shared sequence integrates and records.

    parts: quantities -> field-output parts (ureterfsi.study.fields); solver: the dataset's `solver` attribute;
    observers: the rung's own, after the probes; attrs, summary: the rung's dataset attributes and the tail
    of the closing progress line, both read once the run has ended; description: follows the cell count
    in the opening progress line."""
    problem: MonolithicFSI
    probes: UreterProbes
    parts: Callable
    solver: str
    observers: list = field(default_factory=list)
    attrs: Callable[[], dict] = dict
    summary: Callable[[], str] = str
    description: str = ""


def integrate_from_rest(pb: MonolithicFSI, settings: TimeSettings, observers,
                        reference_pressure: float) -> TimeIntegrator:
    """Urine at rest at the reference pressure (steady solve, paper §2.4), then time steps to the end;
    a run with a checkpoint resumes from it instead. The integrator holds the step records; remove its
    checkpoint once the run's output is written."""
    integrator = TimeIntegrator(pb, settings, observers)
    if not integrator.has_checkpoint():
        # Newton starts from p = p_ref: for the urine alone (walls at rest) that is the solution, so the
        # steady solve ends after one residual (no Jacobian, no factorisation)
        pb.fill("pressure", reference_pressure)
        its, hist = pb.solve_steady()
        log.info("initial state: urine at rest at the reference pressure, %d Newton iterations, residual %.2e",
                 its, hist[-1])
    integrator.run()
    return integrator


def rank_usage(comm) -> dict:
    """What the ranks used, measured by themselves (a batch system's record of an `srun` job step may measure its
    client): peak resident memory summed over the ranks (MiB, from each rank's getrusage ru_maxrss: KiB on
    Linux), the memory a cluster job of this run must reserve, and each rank's CPU time (user + system, s)."""
    use = resource.getrusage(resource.RUSAGE_SELF)
    peaks = comm.allgather(use.ru_maxrss / 1024.0)
    cpu = comm.allgather(use.ru_utime + use.ru_stime)
    return {"peak_memory_mib_all_ranks": round(sum(peaks), 1), "cpu_time_s_per_rank": [round(c, 2) for c in cpu]}


def run(cfg: dict, spec: RunSpec, out_path: str, checkpoint_path: str | None, fidelity: str,
        pose: Callable[[TimeSettings, object, object, object], Posed], wall_path: str | None = None) -> xr.Dataset:
    """One run of rung `fidelity`: `pose(settings, mesh, cell_tags, facet_tags)` builds the rung's problem
    and probes on the run's mesh; the probe dataset is written atomically (rank 0) to `out_path`."""
    wall0 = _time.perf_counter()
    comm = MPI.COMM_WORLD
    # the mesh first: a file that is not this run's mesh is named before anything hashes it (time_settings)
    mesh, cell_tags, facet_tags = load_mesh(spec.mesh_path, comm, expect=(
        spec.symmetry, cfg["models"][spec.model]["stent"], f"model {spec.model} ({spec.symmetry})"))
    settings = time_settings(cfg, spec, checkpoint_path, fidelity, wall_path)
    posed = pose(settings, mesh, cell_tags, facet_tags)
    pb, obs = posed.problem, posed.probes
    ndofs = pb.W.dofmap.index_map.size_global * pb.W.dofmap.index_map_bs
    ncells = mesh.topology.index_map(mesh.topology.dim).size_global
    log.info("%s model %s, mesh %s (%s): %d cells%s, %d dofs, %d processes, setup %.1f s", fidelity, spec.model,
             spec.level, spec.symmetry, ncells, posed.description, ndofs, comm.size, _time.perf_counter() - wall0)
    fields = field_writer(cfg, out_path, posed.parts, settings.end, comm)
    ends = ends_probes(pb, spec.symmetry)
    integrator = integrate_from_rest(pb, settings, [obs, ends] + posed.observers + ([fields] if fields else []),
                                     cfg["fluid"]["reference_pressure"])
    records = integrator.records
    field_attrs = fields.finish(out_path) if fields else {}
    wall = _time.perf_counter() - wall0
    ds = probes_dataset(obs, records, cfg, spec, field_attrs | {
        "cells": ncells, "dofs": ndofs, "processes": comm.size, "wall_time_s": round(wall, 2),
        "time_step_s": settings.dt, "end_time_s": settings.end, "solver": posed.solver,
        "timings": {k: round(v, 2) for k, v in pb.timings.items()}, "counters": dict(pb.counters)}
        | rank_usage(comm) | posed.attrs(),
        fidelity=fidelity).assign(ends.variables())
    if comm.rank == 0:
        write_netcdf(ds, out_path)
    comm.Barrier()
    integrator.remove_checkpoint()
    log.info("done in %.1f s -> %s%s", wall, out_path, posed.summary())
    pb.close()
    destroy_held(posed)         # the rung's own solvers (the one-way stent's LU) and probes
    return ds
