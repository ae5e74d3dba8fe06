"""The workflow's resource decisions as plain functions of the configuration: the local memory budget, a solve's
memory reservation and out-of-core factorisation, the scheduling priority of a level and of a solve, and the MPI
launcher of a solve's command line. workflow/rules/common.smk wraps them for the rules."""
from __future__ import annotations

import sys


def local_memory_budget(cfg: dict, physical_mib: int) -> int:
    """MiB a local run may reserve in all (global resource mem_mb): the machine's memory less
    study.memory_headroom_mb."""
    return int(physical_mib) - int(cfg["study"]["memory_headroom_mb"])


def level_priority(cfg: dict, level: str) -> int:
    """Scheduling priority of a level's mesh and solve jobs: finer levels first (longest job first: the fine
    run of the mesh study is the critical path of the default reproduction)."""
    levels = cfg["mesh"]["levels"]
    factors = sorted({float(v["size_factor"]) for v in levels.values()}, reverse=True)
    return factors.index(float(levels[level]["size_factor"]))


def solve_priority(cfg: dict, model: str, level: str) -> int:
    """Scheduling priority of a study solve and of its mesh: by level as level_priority, then within a level by the
    model's side holes (the mesh, and the run's cost, grow with them: coarse models 2, 3, 4 took 722, 651, 557 s on
    one day, docs/performance.md), so that the longest jobs start first and the shortest fill the slot the fine run
    leaves."""
    models = cfg["models"]
    order = sorted(models, key=lambda m: (bool(models[m]["stent"]), int(models[m]["holes"]), m))
    return level_priority(cfg, level) * len(models) + order.index(str(model))


def wall_priority(cfg: dict) -> int:
    """Scheduling priority of the one-way rung's r-z wall solve, which every one-way run waits for: above every
    solve_priority."""
    return 1 + max(solve_priority(cfg, m, level) for m in cfg["models"] for level in cfg["mesh"]["levels"])


def memory_entry(fidelity: str, scheme: str) -> str:
    """The study.memory_mb entry of a 3D solve: its fidelity, but `partitioned` for the fully coupled rung solved by
    partitioned sweeps (solver.fully_coupled_scheme), which holds ~1/4 of the memory of Newton on the whole system
    (docs/performance.md)."""
    return "partitioned" if fidelity == "fully_coupled" and scheme == "partitioned" else fidelity


def solve_mem_mb(cfg: dict, fidelity: str, symmetry: str, level: str, scheme: str | None = None) -> int:
    """MiB a solve reserves (resource mem_mb) from study.memory_mb: r-z runs reserve `axisymmetric`, 3D runs
    their entry (memory_entry; `scheme` the solve's solver.fully_coupled_scheme, None: cfg's) for the level (a level
    without one: that entry's largest; the entries are for quarter meshes) times the symmetry's factor."""
    table = cfg["study"]["memory_mb"]
    if symmetry == "axisymmetric":
        return int(table["axisymmetric"])
    per_level = table[memory_entry(fidelity, scheme or cfg["solver"]["fully_coupled_scheme"])]
    return int(per_level.get(level, max(per_level.values())) * table["symmetry_factor"][symmetry])


def out_of_core(cfg: dict, fidelity: str, symmetry: str, level: str, budget_mb, scheme: str | None = None) -> int:
    """1 for a fully coupled solve that reserves more memory than the local budget (None: no budget, a
    cluster run) holds: MUMPS then keeps its factors on disk, the same solution in a fraction of the memory
    (docs/performance.md); else 0."""
    reserved = solve_mem_mb(cfg, fidelity, symmetry, level, scheme)
    return int(fidelity == "fully_coupled" and budget_mb is not None and reserved > int(budget_mb))


def node_refusal(cfg: dict, fidelity: str, symmetry: str, level: str, node_mb, scheme: str | None = None) -> str:
    """Why a solve cannot run on a node of `node_mb` MiB (cluster.mem_mb_per_node; None: unknown), '' if it can: it
    reserves more than the node has and cannot keep its factors on disk (out_of_core against the node)."""
    need = solve_mem_mb(cfg, fidelity, symmetry, level, scheme)
    if node_mb is None or need <= int(node_mb) or out_of_core(cfg, fidelity, symmetry, level, node_mb, scheme):
        return ""
    return f"needs {need} MiB (study.memory_mb), more than a node has (cluster.mem_mb_per_node: {int(node_mb)})"


def mpi_solve(fidelity: str, symmetry: str) -> bool:
    """Whether a solve may run on several MPI ranks: the fully coupled rung in 3D (the one-way rung and the
    r-z runs are serial)."""
    return fidelity == "fully_coupled" and symmetry != "axisymmetric"


def mpi_resource(fidelity: str, symmetry: str) -> str | None:
    """Resource mpi of a solve: the local launcher for an MPI-capable solve, none (a serial job) otherwise."""
    return "mpiexec" if mpi_solve(fidelity, symmetry) else None


def launcher(fidelity: str, symmetry: str, tasks: int = 1, mpi: str | None = None,
             python: str = sys.executable) -> str:
    """The interpreter of `-m ureterfsi.study`, behind `<mpi> -n <tasks>` when an MPI-capable solve has more
    than one task."""
    if int(tasks) > 1 and mpi_solve(fidelity, symmetry):
        return f"{mpi} -n {int(tasks)} {python}"
    return python
