# FSI solves (paper §2.2-2.4): one run per model, mesh level and fidelity rung (fully_coupled: the
# monolithic ALE model; one_way: wall -> urine -> stent, serial).
# A fully coupled 3D run may be an MPI job: resources.tasks ranks under resources.mpi (mpiexec locally,
# srun on SLURM); every other solve is a serial job without the mpi resource.
# A killed run resumes from its checkpoint when Snakemake starts it again (checkpoints are kept outside
# the job's outputs, so Snakemake's clean-up of incomplete outputs does not remove them).
# The command of every solve rule: ureterfsi.workflow.launch (params solve, common.smk's solve_command).


rule solve_config:
    output:
        run_config_file("{fidelity}", "{model}"),
    log:
        paths.log("solve/config/{fidelity}/model{model}"),
    localrule: True
    params:
        # rerun trigger and the file's content: the configuration one solve of the model reads on the rung
        sections=lambda w: run_sections(config, w.model, w.fidelity),
    script:
        "../scripts/solve_config.py"


rule wall_motion:
    """Step 1 of the one-way rung: the ureter wall alone (r-z) over [0, time.end], once for every one-way run
    (their wall is the same: geometry and load do not depend on the stent model or the 3D mesh).
    """
    output:
        paths.WALL_MOTION,
    log:
        paths.log("solve/one_way/wall_motion"),
    benchmark:
        paths.benchmark("solve/one_way/wall_motion")
    priority: decide.wall_priority(config)
    threads: 1
    resources:
        mem_mb=config["study"]["memory_mb"]["axisymmetric"],
    params:
        wall=lambda w: json.dumps(wall_sections(config), sort_keys=True),
    script:
        "../scripts/wall_motion.py"


rule solve:
    input:
        unpack(solve_inputs),
    output:
        paths.run(),
    log:
        paths.log("solve/{fidelity}/{symmetry}/model{model}_{level}"),
    benchmark:
        paths.benchmark("solve/{fidelity}/{symmetry}/model{model}_{level}")
    priority: solve_priority
    threads: 1
    resources:
        tasks=1,
        mpi=solve_mpi(study_rung),
        mem_mb=solve_mem_mb_of(
            study_rung, lambda w: paths.run(w.fidelity, w.symmetry, w.model, w.level)
        ),
        runtime=24 * 60,
        mumps_out_of_core=out_of_core(study_rung),
    params:
        # rerun triggers (the command is not one: a function of resources)
        checkpoint=paths.checkpoint("{fidelity}/{symmetry}/model{model}_{level}"),
        end=convergence_only_end,
        solve=solve_command(study_job),
    shell:
        launch.SHELL
