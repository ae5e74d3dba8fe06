"""The configuration sections each job reads: a change re-runs the job (its rerun trigger) and a file made from
other values is refused. The one list of them: rule mesh, rule solve (and design_solve), the one-way rung's wall."""
from __future__ import annotations

from .end_pressures import wall_pressure_posed
from .schema import schema_defaults

# the geometry the r-z wall solve reads (ureterfsi.scenes.wall_rz.WallModel): the stent and its holes do not enter
WALL_GEOMETRY = ("length", "ureter_outer_diameter", "ureter_wall_thickness", "stricture_fraction", "stricture_length",
                 "stricture_position")


RUN_SECTIONS = ("geometry", "fluid", "ureter", "stent", "peristalsis", "time", "mesh", "solver", "fields",
                "stent_surface")
# sections a solve reads that enter its configuration only where they differ from the schema's defaults (the paper's
# setting): a run of the defaults reads them from the schema, so adding such a section re-runs no solve
DEFAULTED_RUN_SECTIONS = ("ends",)


# the keys one fidelity rung alone reads (section.key): a run on the other rung holds them at the schema's defaults,
# so that changing one re-runs no solve of the other rung. one_way: the urine step of ureterfsi.study.oneway and its
# a-priori wall pressure; fully_coupled: its scheme and linear solver (study.options.solver_options) and the
# partitioned scheme's sweeps and blocks (fsi.partitioned, fsi.block_forms)
RUNG_KEYS = {
    "one_way": ("solver.one_way_newton_field_rtol", "solver.one_way_mesh_motion", "solver.one_way_urine_step",
                "solver.one_way_auto_min_jacobian", "solver.one_way_reuse_contraction",
                "ends.one_way_pressure_tolerance"),
    "fully_coupled": ("solver.fully_coupled_linear_solver", "solver.fully_coupled_scheme", "solver.anderson_depth",
                      "solver.anderson_reuse", "solver.block_iterations", "solver.block_reuse_contraction",
                      "solver.block_refresh_sweeps", "solver.solid_block", "solver.wall_jacobian_quadrature_degree",
                      "solver.sweep_convergence"),
}


def rung_view(cfg: dict, fidelity: str) -> dict:
    """`cfg` with the keys only the other rungs read (RUNG_KEYS) at the schema's defaults (a shallow copy down to
    the sections it changes)."""
    if fidelity not in RUNG_KEYS:
        raise ValueError(f"fidelity must be one of {sorted(RUNG_KEYS)}, got {fidelity!r}")
    other = [k.split(".") for rung, keys in RUNG_KEYS.items() if rung != fidelity for k in keys]
    out = dict(cfg)
    for section in {s for s, _ in other}:
        defaults = schema_defaults(section)
        out[section] = dict(out[section]) | {k: defaults[k] for s, k in other if s == section}
    return out


def run_sections(cfg: dict, model: str, fidelity: str) -> dict:
    """The configuration one solve of `model` on rung `fidelity` reads (RUN_SECTIONS, DEFAULTED_RUN_SECTIONS off
    their defaults and its entry of `models`; the other rungs' keys at their defaults, rung_view): a change re-runs
    the solve (rule `solve`), and a checkpoint made from other values is not resumed (ureterfsi.study)."""
    cfg = rung_view(cfg, fidelity)
    off = {k: cfg[k] for k in DEFAULTED_RUN_SECTIONS if cfg[k] != schema_defaults(k)}
    return {k: cfg[k] for k in RUN_SECTIONS} | off | {"model": cfg["models"][model]}


def mesh_sections(cfg: dict, model: str, level: str, symmetry: str) -> dict:
    """The configuration entering a mesh (rule mesh's rerun trigger) with its level and symmetry."""
    return {"geometry": cfg["geometry"], "mesh": cfg["mesh"], "model": cfg["models"][model],
            "level": level, "symmetry": symmetry}


def wall_sections(cfg: dict) -> dict:
    """The configuration the one-way rung's r-z wall solve reads (ureterfsi.study.oneway.wall_history): a change
    re-runs the shared wall-motion job, and a wall-motion file made from other values is refused. The end conditions
    enter where an end is not open (the urine pressure the wall then takes, config.end_pressures.wall_pressure)."""
    ends = {"ends": {k: cfg["ends"][k] for k in ("kidney", "bladder")}} if wall_pressure_posed(cfg) else {}
    return {"geometry": {k: cfg["geometry"][k] for k in WALL_GEOMETRY}} | {
        k: cfg[k] for k in ("ureter", "peristalsis", "time")} | {
        "solver": {k: cfg["solver"][k] for k in ("predictor", "max_step_halvings")}} | ends
