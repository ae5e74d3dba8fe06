# Fidelity ladder (issue 5): runs of config `ladder.model` on each rung (fidelity, symmetry, mesh level,
# time step) over [0, ladder.end], measured against the reference rung -> dataset, speed-accuracy figure and
# table (ureterfsi.ladder). Target: `snakemake --cores 2 ladder` (not part of `all`: the fully coupled
# reference is the expensive run this ladder exists to avoid).

LADDER = config.get("ladder")

if LADDER:
    LADDER_RUNGS = LADDER["rungs"]

    wildcard_constraints:
        rung="|".join(LADDER_RUNGS),

    rule ladder_run:
        input:
            mesh=lambda w: "results/meshes/{symmetry}/model{model}_{level}.msh".format(
                model=LADDER["model"], **LADDER_RUNGS[w.rung]),
        output:
            "results/ladder/{rung}.nc",
        params:
            study=lambda w: study_subset(SimpleNamespace(model=LADDER["model"])),
            rung=lambda w: LADDER_RUNGS[w.rung],
            end=LADDER["end"],
        log:
            "results/logs/ladder/{rung}.log",
        benchmark:
            "results/benchmarks/ladder/{rung}.tsv"
        threads: 1
        resources:
            mem_mb=lambda w: solve_mem_mb(**{k: LADDER_RUNGS[w.rung][k] for k in ("fidelity", "symmetry", "level")}),
            runtime=24 * 60,
        run:
            r = params.rung
            solve_command(config, model=LADDER["model"], level=r["level"], symmetry=r["symmetry"],
                          fidelity=r["fidelity"], mesh=input.mesh, out=output[0], log=log[0], threads=threads,
                          extra=f"--end {params.end} --dt {r['dt']}")

    rule ladder:
        input:
            runs=expand("results/ladder/{rung}.nc", rung=LADDER_RUNGS),
        output:
            dataset="results/datasets/ladder.nc",
            md=report("results/figures/table_ladder.md", caption="../report/table_ladder.rst",
                      category="Fidelity ladder"),
            figures=[report(f"results/figures/ladder_pareto.{ext}", caption="../report/ladder_pareto.rst",
                            category="Fidelity ladder") if ext == REPORT_FORMAT
                     else f"results/figures/ladder_pareto.{ext}" for ext in FIGURE_FORMATS],
        params:
            rungs=list(LADDER_RUNGS),
            figures=FIGURE_OPTIONS,
            # the scenes' tolerances and recorded errors: a change re-runs the check (table_ladder.md)
            scenes=config["scenes"],
            ladder=config["ladder"],
        log:
            "results/logs/ladder/ladder.log",
        script:
            "../scripts/ladder.py"
