# Study datasets (paper §3): the per-run probe files combined across stent models (one mesh level) and
# across mesh levels (mesh-convergence study, paper §3.1). ureterfsi.analyses.aggregate reads model, level and
# symmetry from each file's attributes; the rules only choose which runs enter.


rule aggregate_models:
    input:
        runs=lambda w: [run_file(m, w.level) for m in MODELS],
    output:
        paths.dataset("models_{level}"),
    log:
        paths.log("aggregate/models_{level}"),
    threads: 1
    params:
        # rerun triggers: the Table 1 labels stored in the dataset and the time-grid choice
        labels={m: config["models"][m]["label"] for m in MODELS},
        time_grid="union",
        # what each run file must be (a file of another model, level, rung or symmetry is refused)
        expect=lambda w: {
            run_file(m, w.level): {
                "model": m,
                "mesh_level": w.level,
                "fidelity": run_fidelity(m),
                "symmetry": run_symmetry(m),
            }
            for m in MODELS
        },
    script:
        "../scripts/aggregate_models.py"


rule aggregate_convergence:
    input:
        runs=[run_file(CONVERGENCE_MODEL, lv) for lv in LEVELS],
    output:
        paths.dataset("mesh_convergence"),
    log:
        paths.log("aggregate/mesh_convergence"),
    threads: 1
    params:
        time=config["study"]["convergence_time"],
        levels=LEVELS,
    script:
        "../scripts/aggregate_convergence.py"


# Grid Convergence Index (Celik et al. 2008) of the mesh-convergence study: peak outlet flux, peak maximum
# stent von Mises stress and the probe-line stress at GCI_POINTS_Z, from the three finest levels
# (ureterfsi.analyses.gci). h = (V/N)^(1/3) with V the analytic volume of the mesh (the same on every level; read from
# the last level's mesh sidecar). Needs at least three mesh levels (all_figures asks for it only then).
# probe-line points: a quarter, half and three quarters of the segment (12.5, 25, 37.5 mm for L = 50 mm)
GCI_POINTS_Z = [
    round(f * float(config["geometry"]["length"]), 9) for f in (0.25, 0.5, 0.75)
]
GCI_SAFETY_FACTOR = 1.25  # Celik et al. 2008, three grids


rule gci:
    input:
        conv=paths.dataset("mesh_convergence"),
        mesh=mesh_sidecar(CONVERGENCE_MODEL, LEVELS[-1]),
    output:
        paths.dataset("mesh_convergence_gci"),
    log:
        paths.log("aggregate/mesh_convergence_gci"),
    threads: 1
    params:
        points_z=GCI_POINTS_Z,
        safety_factor=GCI_SAFETY_FACTOR,
    script:
        "../scripts/gci.py"
