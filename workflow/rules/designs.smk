# Design studies (config `design_studies`, ureterfsi.designs.space): every point its own chain of jobs.
# Meshes and wall motions are content-addressed (shared by every point with the same geometry / wall):
#   results/designs/meshes/{mesh_id}.msh        design_mesh
#   results/designs/wall_motion/{wall_id}.nc    design_wall_motion (one-way rung)
#   results/designs/{study}/{point}/run.nc      design_solve
#   results/designs/{study}/rung_check/{corner}/{rung}.nc   design_corner_solve: a corner of the design space on
#       the segment, on the study's rung and fully coupled (ureterfsi.designs.rung_check); a corner that is a point of a
#       study on the segment reuses the point's run
#   results/designs/{study}/rung_check.nc       design_rung_check: the rung error per corner and quantity
#   results/designs/{study}.nc                  design_dataset
#   results/figures/designs/{study}_*.{ext}     design_figures, design_map, design_sensitivity
# Targets: design_<study> per study, design_<study>_rung_check (its rung check alone), designs_all.
DESIGN_MESHES = {
    p.mesh_id: (st, p)
    for st in DESIGNS.values()
    for p in st.points + (st.check.corners if st.check else [])
}
DESIGN_WALLS = {
    p.wall_id: p
    for st in DESIGNS.values()
    for p in st.points + (st.check.corners if st.check else [])
    if p.wall_id
}


if DESIGNS:

    wildcard_constraints:
        design_study="|".join(DESIGNS),
        point="[0-9a-f]{10}",
        corner="[0-9a-f]{10}",
        corner_rung="one_way|fully_coupled",
        mesh_id="[0-9a-f]{10}",
        wall_id="[0-9a-f]{10}",

    rule design_mesh:
        output:
            msh="results/designs/meshes/{mesh_id}.msh",
            json="results/designs/meshes/{mesh_id}.json",
        log:
            "results/logs/designs/meshes/{mesh_id}.log",
        benchmark:
            "results/benchmarks/designs/meshes/{mesh_id}.tsv"
        threads: 1
        params:
            inputs=design_mesh_inputs,
        script:
            "../scripts/design_mesh.py"

    rule design_wall_motion:
        output:
            "results/designs/wall_motion/{wall_id}.nc",
        log:
            "results/logs/designs/wall_motion/{wall_id}.log",
        benchmark:
            "results/benchmarks/designs/wall_motion/{wall_id}.tsv"
        threads: 1
        resources:
            mem_mb=config["study"]["memory_mb"]["axisymmetric"],
        params:
            wall=lambda w: json.dumps(
                wall_sections(DESIGN_WALLS[w.wall_id].config), sort_keys=True
            ),
        script:
            "../scripts/design_wall_motion.py"

    rule design_solve:
        input:
            unpack(design_solve_inputs),
        output:
            "results/designs/{design_study}/{point}/run.nc",
        log:
            "results/logs/designs/{design_study}/{point}.log",
        benchmark:
            "results/benchmarks/designs/{design_study}/{point}.tsv"
        threads: 1
        resources:
            mem_mb=design_solve_mem_mb,
            runtime=24 * 60,
        params:
            study=design_solve_study,
            checkpoint="results/checkpoints/designs/{design_study}/{point}.npz",
        script:
            "../scripts/design_solve.py"

    rule design_corner_solve:
        input:
            unpack(design_corner_inputs),
        output:
            "results/designs/{design_study}/rung_check/{corner}/{corner_rung}.nc",
        log:
            "results/logs/designs/{design_study}/rung_check/{corner}_{corner_rung}.log",
        benchmark:
            "results/benchmarks/designs/{design_study}/rung_check/{corner}_{corner_rung}.tsv"
        threads: 1
        resources:
            mem_mb=design_corner_mem_mb,
            runtime=24 * 60,
        params:
            study=design_corner_study,
            checkpoint="results/checkpoints/designs/{design_study}/rung_check/{corner}_{corner_rung}.npz",
        script:
            "../scripts/design_solve.py"

    rule design_rung_check:
        input:
            design_corner_runs,
        output:
            "results/designs/{design_study}/rung_check.nc",
        log:
            "results/logs/designs/{design_study}_rung_check.log",
        threads: 1
        script:
            "../scripts/design_rung_check.py"

    rule design_dataset:
        input:
            unpack(design_dataset_inputs),
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
            design_figure_outputs("parameters"),
        log:
            "results/logs/designs/{design_study}_figures.log",
        params:
            dpi=FIGURE_OPTIONS["dpi"],
            rung_check=design_rung_check_caption,
        script:
            "../scripts/design_figures.py"

    rule design_map:
        input:
            "results/designs/{design_study}.nc",
        output:
            design_figure_outputs("map"),
        log:
            "results/logs/designs/{design_study}_map.log",
        params:
            dpi=FIGURE_OPTIONS["dpi"],
            rung_check=design_rung_check_caption,
        script:
            "../scripts/design_figures.py"

    rule design_sensitivity:
        input:
            "results/designs/{design_study}.nc",
        output:
            design_figure_outputs("sensitivity"),
        log:
            "results/logs/designs/{design_study}_sensitivity.log",
        params:
            dpi=FIGURE_OPTIONS["dpi"],
            rung_check=design_rung_check_caption,
        script:
            "../scripts/design_figures.py"

    for _study in DESIGNS:

        rule:
            name:
                f"design_{_study}"
            input:
                f"results/designs/{_study}.nc",
                design_figures(_study),

        if DESIGNS[_study].check:

            rule:
                name:
                    f"design_{_study}_rung_check"
                input:
                    f"results/designs/{_study}/rung_check.nc",

    rule designs_all:
        input:
            [f"results/designs/{s}.nc" for s in DESIGNS],
            [f for s in DESIGNS for f in design_figures(s)],
