# Design studies (config `design_studies`, ureterfsi.designs.space): every point its own chain of jobs.
# Meshes and wall motions are content-addressed (shared by every point with the same geometry / wall). The
# rules (their paths: ureterfsi.workflow.paths): design_mesh, design_wall_motion (one-way rung), design_solve
# (a point or a reference run), design_corner_solve (a corner of the design space on the segment, on the study's
# rung and fully coupled, ureterfsi.designs.rung_check; a corner that is a point of a study on the segment reuses
# the point's run), the checkpoint design_rung_check (the rung error per corner and quantity; under
# rung_check.on_failure: escalate, design_dataset's input function reads it and asks design_escalated_solve for
# the points nearest a failing corner), design_dataset, and the figures (design_figures, design_map,
# design_sensitivity, design_passage; design_field_hole_flow and design_field_stent_wss of the points the study's
# field_figures selects), and design_question (the spacing's effect on the outlet flow over every study varying it).
# Targets: design_<study> per study, design_<study>_rung_check (its rung check alone), design_question, designs_all.
# Their inputs, rerun triggers and solves: ureterfsi.designs.jobs; the solve command: common.smk's solve_command.

DESIGN_MESHES = design_jobs.meshes(DESIGNS)
DESIGN_WALLS = design_jobs.walls(DESIGNS)

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
            msh=paths.design_mesh(),
            json=paths.design_mesh(ext="json"),
        log:
            paths.log("designs/meshes/{mesh_id}"),
        benchmark:
            paths.benchmark("designs/meshes/{mesh_id}")
        threads: 1
        params:
            inputs=design_mesh_inputs,
        script:
            "../scripts/design_mesh.py"

    rule design_wall_motion:
        output:
            paths.design_wall_motion(),
        log:
            paths.log("designs/wall_motion/{wall_id}"),
        benchmark:
            paths.benchmark("designs/wall_motion/{wall_id}")
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
            paths.design_run(),
        log:
            paths.log("designs/{design_study}/{point}"),
        benchmark:
            paths.benchmark("designs/{design_study}/{point}")
        threads: 1
        resources:
            tasks=1,
            mpi=solve_mpi(point_rung),
            mem_mb=solve_mem_mb_of(
                point_rung,
                lambda w: paths.design_run(w.design_study, w.point),
                point_scheme,
            ),
            runtime=24 * 60,
            mumps_out_of_core=out_of_core(point_rung, point_scheme),
        params:
            # rerun triggers (the command is not one: a function of resources)
            study=lambda w: design_jobs.solve_trigger(point_solve(w)),
            checkpoint=paths.checkpoint("designs/{design_study}/{point}"),
            solve=solve_command(point_job),
        shell:
            launch.SHELL

    rule design_escalated_solve:
        input:
            unpack(design_escalated_inputs),
        output:
            paths.escalated_run(),
        log:
            paths.log("designs/{design_study}/{point}_fully_coupled"),
        benchmark:
            paths.benchmark("designs/{design_study}/{point}_fully_coupled")
        threads: 1
        resources:
            tasks=1,
            mpi=solve_mpi(escalated_rung),
            mem_mb=solve_mem_mb_of(
                escalated_rung,
                lambda w: paths.escalated_run(w.design_study, w.point),
                escalated_scheme,
            ),
            runtime=24 * 60,
            mumps_out_of_core=out_of_core(escalated_rung, escalated_scheme),
        params:
            # rerun triggers (the command is not one: a function of resources)
            study=lambda w: design_jobs.solve_trigger(escalated_solve(w)),
            checkpoint=paths.checkpoint("designs/{design_study}/{point}_fully_coupled"),
            solve=solve_command(escalated_job),
        shell:
            launch.SHELL

    rule design_corner_solve:
        input:
            unpack(design_corner_inputs),
        output:
            paths.corner_run(),
        log:
            paths.log("designs/{design_study}/rung_check/{corner}_{corner_rung}"),
        benchmark:
            paths.benchmark("designs/{design_study}/rung_check/{corner}_{corner_rung}")
        threads: 1
        resources:
            tasks=1,
            mpi=solve_mpi(corner_rung),
            mem_mb=solve_mem_mb_of(
                corner_rung,
                lambda w: paths.corner_run(w.design_study, w.corner, w.corner_rung),
                corner_scheme,
            ),
            runtime=24 * 60,
            mumps_out_of_core=out_of_core(corner_rung, corner_scheme),
        params:
            # rerun triggers (the command is not one: a function of resources)
            study=lambda w: design_jobs.solve_trigger(corner_solve(w)),
            checkpoint=paths.checkpoint(
                "designs/{design_study}/rung_check/{corner}_{corner_rung}"
            ),
            solve=solve_command(corner_job),
        shell:
            launch.SHELL

    checkpoint design_rung_check:
        input:
            design_corner_runs,
        output:
            paths.rung_check(),
        log:
            paths.log("designs/{design_study}_rung_check"),
        threads: 1
        script:
            "../scripts/design_rung_check.py"

    rule design_dataset:
        input:
            unpack(design_dataset_inputs),
        output:
            paths.design_dataset(),
        log:
            paths.log("designs/{design_study}_dataset"),
        threads: 1
        script:
            "../scripts/design_dataset.py"

    rule design_figures:
        input:
            paths.design_dataset(),
        output:
            design_figure_outputs("parameters"),
        log:
            paths.log("designs/{design_study}_figures"),
        params:
            dpi=FIGURE_OPTIONS["dpi"],
            rung_check=design_rung_check_caption,
        script:
            "../scripts/design_figures.py"

    rule design_map:
        input:
            paths.design_dataset(),
        output:
            design_figure_outputs("map"),
        log:
            paths.log("designs/{design_study}_map"),
        params:
            dpi=FIGURE_OPTIONS["dpi"],
            rung_check=design_rung_check_caption,
        script:
            "../scripts/design_figures.py"

    rule design_sensitivity:
        input:
            paths.design_dataset(),
        output:
            design_figure_outputs("sensitivity"),
        log:
            paths.log("designs/{design_study}_sensitivity"),
        params:
            dpi=FIGURE_OPTIONS["dpi"],
            rung_check=design_rung_check_caption,
        script:
            "../scripts/design_figures.py"

    rule design_passage:
        input:
            paths.design_dataset(),
        output:
            design_figure_outputs("passage"),
        log:
            paths.log("designs/{design_study}_passage"),
        params:
            dpi=FIGURE_OPTIONS["dpi"],
            rung_check=design_rung_check_caption,
        script:
            "../scripts/design_figures.py"

    rule design_field_hole_flow:
        input:
            run=paths.design_run(),
        output:
            design_field_figure_outputs("field_hole_flow"),
        log:
            paths.log("designs/{design_study}_{point}_field_hole_flow"),
        params:
            dpi=FIGURE_OPTIONS["dpi"],
            point_config=design_point_config,
            point_values=design_point_values,
        script:
            "../scripts/design_field_figures.py"

    rule design_field_stent_wss:
        input:
            run=paths.design_run(),
        output:
            design_field_figure_outputs("field_stent_wss"),
        log:
            paths.log("designs/{design_study}_{point}_field_stent_wss"),
        params:
            dpi=FIGURE_OPTIONS["dpi"],
            point_config=design_point_config,
            point_values=design_point_values,
        script:
            "../scripts/design_field_figures.py"

    for _study in DESIGNS:

        rule:
            name:
                f"design_{_study}"
            input:
                paths.design_dataset(_study),
                design_figures(_study),
                # every point's run up front: under escalate the dataset's inputs wait for the rung check
                design_jobs.runs(DESIGNS[_study]),

        if DESIGNS[_study].check:

            rule:
                name:
                    f"design_{_study}_rung_check"
                input:
                    paths.rung_check(_study),

    rule design_question:
        input:
            question_datasets(),
        output:
            paths.design_question(),
        log:
            paths.log("designs/question"),
        script:
            "../scripts/design_question.py"

    rule designs_all:
        input:
            [paths.design_dataset(s) for s in DESIGNS],
            [f for s in DESIGNS for f in design_figures(s)],
            [paths.design_question()] if question_datasets() else [],
