"""The configuration of one run as the engine's options: what a run is (RunSpec), its solver options and its
time stepping, with the identity a checkpoint is bound to."""
from __future__ import annotations

import json
from dataclasses import dataclass

import dolfinx

from ureterfsi import __version__
from ureterfsi.data.checked import sha256_file
from ..config import run_sections
from ..fsi import SolverOptions, TimeSettings

FIDELITIES = ("fully_coupled", "one_way")   # rungs of the fidelity ladder a run can use


@dataclass
class RunSpec:
    model: str
    level: str
    symmetry: str
    mesh_path: str
    end: float | None = None       # override of time.end (short test runs)
    dt: float | None = None        # override of time.dt
    # fully coupled: MUMPS's factors on disk (SolverOptions.mumps_out_of_core), for a job given less memory than
    # its reservation (rule solve); not part of the run's identity: the same factors, the same solution
    out_of_core: bool = False


def solver_options(cfg: dict, fully_coupled: bool = False) -> SolverOptions:
    """The engine's options from `solver`; `fully_coupled`: the fully coupled rung's solve, whose scheme and linear
    solver are `solver.fully_coupled_scheme` and `solver.fully_coupled_linear_solver`."""
    s = cfg["solver"]
    return SolverOptions(mesh_motion=s["mesh_motion"], mesh_stiffening=s["mesh_stiffening"],
                         newton_rtol=s["newton_rtol"], newton_atol=s["newton_atol"],
                         newton_field_rtol=s["newton_field_rtol"],
                         newton_max_iterations=s["newton_max_iterations"], predictor=s["predictor"],
                         linear_solver=s["fully_coupled_linear_solver"] if fully_coupled else s["linear_solver"],
                         reuse_jacobian=s["reuse_jacobian"], reuse_contraction=s["reuse_contraction"],
                         mesh_motion_direct_max_unknowns=int(s["mesh_motion_direct_max_unknowns"]),
                         krylov_rtol=s["krylov_rtol"], krylov_forcing=s["krylov_forcing"],
                         krylov_refactorise_iterations=s["krylov_refactorise_iterations"],
                         coupling_scheme=s["fully_coupled_scheme"] if fully_coupled else "monolithic",
                         anderson_depth=s["anderson_depth"], anderson_reuse=s["anderson_reuse"],
                         block_iterations=s["block_iterations"],
                         block_reuse_contraction=s["block_reuse_contraction"],
                         block_refresh_sweeps=s["block_refresh_sweeps"], solid_block=s["solid_block"],
                         sweep_convergence=s["sweep_convergence"],
                         wall_jacobian_quadrature_degree=s["wall_jacobian_quadrature_degree"])


def time_settings(cfg: dict, spec: RunSpec, checkpoint_path: str | None, fidelity: str = "fully_coupled",
                  wall_path: str | None = None) -> TimeSettings:
    """Time stepping of a run: config `time` with the run's end/dt overrides, checkpoints if a path is given
    (bound to the run's identity, run_identity)."""
    tcfg = cfg["time"]
    settings = TimeSettings(end=spec.end or tcfg["end"], dt=spec.dt or tcfg["dt"], output_times=tcfg["probe_times"],
                            max_halvings=cfg["solver"]["max_step_halvings"],
                            checkpoint_interval=tcfg["checkpoint_interval"] if checkpoint_path else 0,
                            checkpoint_path=checkpoint_path)
    if checkpoint_path:
        settings.identity = run_identity(cfg, spec, fidelity, settings.end, settings.dt, wall_path)
    return settings


def _flatten(prefix: str, value, out: dict) -> None:
    if isinstance(value, dict):
        for k, v in value.items():
            _flatten(f"{prefix}.{k}" if prefix else str(k), v, out)
    else:
        out[prefix] = json.dumps(value, sort_keys=True)



def run_identity(cfg: dict, spec: RunSpec, fidelity: str, end: float, dt: float, wall_path: str | None = None) -> dict:
    """What determines a run, component -> value (TimeSettings.identity): every key of the configuration
    sections it reads on its rung (ureterfsi.config.run_sections), the run's model, mesh level, symmetry, fidelity,
    end and dt, the SHA-256 of the mesh file (and of the wall-motion file of a one-way run), and the
    versions of ureterfsi and dolfinx."""
    out: dict = {}
    sections = run_sections(cfg, spec.model, fidelity)
    _flatten(f"models.{spec.model}", sections.pop("model"), out)
    _flatten("", sections, out)
    out.update({"run.model": spec.model, "run.level": spec.level, "run.symmetry": spec.symmetry,
                "run.fidelity": fidelity, "run.end": repr(float(end)), "run.dt": repr(float(dt)),
                "mesh_sha256": sha256_file(spec.mesh_path, kind="gmsh mesh"),
                "version.ureterfsi": __version__, "version.dolfinx": dolfinx.__version__})
    if wall_path:
        out["wall_motion_sha256"] = sha256_file(wall_path, kind="wall-motion file")
    return out
