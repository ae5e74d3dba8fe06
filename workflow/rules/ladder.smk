# Fidelity ladder: runs of config `ladder.model` on each rung (fidelity, symmetry, mesh level,
# time step) over [0, ladder.end], measured against the reference rung -> dataset, speed-accuracy figure and
# table (ureterfsi.analyses.ladder). Target: `snakemake --cores 2 ladder` (not part of `all`: the fully coupled
# reference is the expensive run this ladder exists to avoid). A killed rung resumes from its checkpoint.

LADDER = config.get("ladder")

if LADDER:
    LADDER_RUNGS = LADDER["rungs"]

    wildcard_constraints:
        rung="|".join(LADDER_RUNGS),

    rule ladder_run:
        input:
            mesh=lambda w: paths.mesh(
                LADDER_RUNGS[w.rung]["symmetry"],
                LADDER["model"],
                LADDER_RUNGS[w.rung]["level"],
            ),
            config=lambda w: run_config_file(
                LADDER_RUNGS[w.rung]["fidelity"], LADDER["model"]
            ),
        output:
            paths.ladder_run(),
        log:
            paths.log("ladder/{rung}"),
        benchmark:
            paths.benchmark("ladder/{rung}")
        threads: 1
        resources:
            tasks=1,
            mpi=solve_mpi(ladder_rung),
            mem_mb=solve_mem_mb_of(ladder_rung, lambda w: paths.ladder_run(w.rung)),
            runtime=24 * 60,
            mumps_out_of_core=out_of_core(ladder_rung),
        params:
            # rerun triggers (the command is not one: a function of resources)
            rung=lambda w: LADDER_RUNGS[w.rung],
            end=LADDER["end"],
            model=LADDER["model"],
            checkpoint=paths.checkpoint("ladder/{rung}"),
            solve=solve_command(ladder_job),
        shell:
            launch.SHELL

    rule ladder:
        input:
            runs=expand(paths.ladder_run(), rung=LADDER_RUNGS),
        output:
            dataset=paths.dataset("ladder"),
            md=report(
                paths.figure("table_ladder", "md"),
                caption="../report/table_ladder.rst",
                category="Fidelity ladder",
            ),
            figures=figure_outputs("ladder_pareto", "Fidelity ladder"),
            overlay=figure_outputs("ladder_overlay", "Fidelity ladder"),
        log:
            paths.log("ladder/ladder"),
        params:
            rungs=list(LADDER_RUNGS),
            figures=FIGURE_OPTIONS,
            # the scenes' tolerances and recorded errors: a change re-runs the check (table_ladder.md)
            scenes=config["scenes"],
            ladder=config["ladder"],
        script:
            "../scripts/ladder.py"
