# Design studies (config `design_studies`, ureterfsi.designs): every point its own chain of jobs.
# Meshes and wall motions are content-addressed (shared by every point with the same geometry / wall):
#   results/designs/meshes/{mesh_id}.msh        design_mesh
#   results/designs/wall_motion/{wall_id}.nc    design_wall_motion (one-way rung)
#   results/designs/{study}/{point}/run.nc      design_solve
#   results/designs/{study}.nc                  design_dataset
#   results/figures/designs/{study}_*.{ext}     design_figures
# Targets: design_<study> per study, designs_all.
import json

from ureterfsi import designs as ureter_designs

DESIGNS = ureter_designs.studies(config)
DESIGN_MESHES = {p.mesh_id: (st, p) for st in DESIGNS.values() for p in st.points}
DESIGN_WALLS = {p.wall_id: p for st in DESIGNS.values() for p in st.points if p.wall_id}


def design_figures(study):
    kinds = ["parameters"] + (["sensitivity"] if DESIGNS[study].kind in ("sobol", "latin_hypercube") else [])
    return [f"results/figures/designs/{study}_{k}.{ext}" for k in kinds for ext in FIGURE_FORMATS]


if DESIGNS:

    wildcard_constraints:
        design_study="|".join(DESIGNS),
        point="[0-9a-f]{10}",
        mesh_id="[0-9a-f]{10}",
        wall_id="[0-9a-f]{10}",

    rule design_mesh:
        output:
            msh="results/designs/meshes/{mesh_id}.msh",
            json="results/designs/meshes/{mesh_id}.json",
        params:
            inputs=lambda w: json.dumps(ureter_designs.mesh_sections(
                DESIGN_MESHES[w.mesh_id][1].config, DESIGN_MESHES[w.mesh_id][0].model,
                DESIGN_MESHES[w.mesh_id][0].level, DESIGN_MESHES[w.mesh_id][0].symmetry), sort_keys=True),
        log:
            "results/logs/designs/meshes/{mesh_id}.log",
        benchmark:
            "results/benchmarks/designs/meshes/{mesh_id}.tsv"
        threads: 1
        script:
            "../scripts/design_mesh.py"

    rule design_wall_motion:
        output:
            "results/designs/wall_motion/{wall_id}.nc",
        params:
            wall=lambda w: json.dumps(wall_sections(DESIGN_WALLS[w.wall_id].config), sort_keys=True),
        log:
            "results/logs/designs/wall_motion/{wall_id}.log",
        benchmark:
            "results/benchmarks/designs/wall_motion/{wall_id}.tsv"
        threads: 1
        resources:
            mem_mb=config["study"]["memory_mb"]["axisymmetric"],
        script:
            "../scripts/design_wall_motion.py"

    def design_solve_inputs(w):
        """The point's mesh, and on the one-way rung its wall motion."""
        p = DESIGNS[w.design_study].point(w.point)
        out = {"mesh": f"results/designs/meshes/{p.mesh_id}.msh"}
        if p.wall_id:
            out["wall"] = f"results/designs/wall_motion/{p.wall_id}.nc"
        return out

    rule design_solve:
        input:
            unpack(design_solve_inputs),
        output:
            "results/designs/{design_study}/{point}/run.nc",
        params:
            study=lambda w: json.dumps(ureter_designs.solve_sections(
                DESIGNS[w.design_study].point(w.point).config, DESIGNS[w.design_study].model)
                | {"rung": DESIGNS[w.design_study].rung, "symmetry": DESIGNS[w.design_study].symmetry}, sort_keys=True),
            checkpoint="results/checkpoints/designs/{design_study}/{point}.npz",
        log:
            "results/logs/designs/{design_study}/{point}.log",
        benchmark:
            "results/benchmarks/designs/{design_study}/{point}.tsv"
        threads: 1
        resources:
            mem_mb=lambda w: solve_mem_mb(DESIGNS[w.design_study].rung, DESIGNS[w.design_study].symmetry,
                                          DESIGNS[w.design_study].level),
            runtime=24 * 60,
        script:
            "../scripts/design_solve.py"

    rule design_dataset:
        input:
            runs=lambda w: [f"results/designs/{w.design_study}/{p.id}/run.nc" for p in DESIGNS[w.design_study].points],
        output:
            "results/designs/{design_study}.nc",
        log:
            "results/logs/designs/{design_study}_dataset.log",
        threads: 1
        script:
            "../scripts/design_dataset.py"

    rule design_figures:
        input:
            "results/designs/{design_study}.nc",
        output:
            [f"results/figures/designs/{{design_study}}_parameters.{ext}" for ext in FIGURE_FORMATS],
        params:
            dpi=FIGURE_OPTIONS["dpi"],
        log:
            "results/logs/designs/{design_study}_figures.log",
        script:
            "../scripts/design_figures.py"

    rule design_sensitivity:
        input:
            "results/designs/{design_study}.nc",
        output:
            [f"results/figures/designs/{{design_study}}_sensitivity.{ext}" for ext in FIGURE_FORMATS],
        params:
            dpi=FIGURE_OPTIONS["dpi"],
        log:
            "results/logs/designs/{design_study}_sensitivity.log",
        script:
            "../scripts/design_figures.py"

    for _study in DESIGNS:

        rule:
            name:
                f"design_{_study}"
            input:
                f"results/designs/{_study}.nc",
                design_figures(_study),

    rule designs_all:
        input:
            [f"results/designs/{s}.nc" for s in DESIGNS],
            [f for s in DESIGNS for f in design_figures(s)],
