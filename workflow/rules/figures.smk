# Figures of the paper (Figs. 2-10), Table 1 and the side-hole flux figure, from the study datasets.
# Every rule's params carry only the plotting options (config `figures`), so changing one re-runs the
# plotting, not the solves or the aggregation. One script draws every figure, chosen by the rule name.

# paper Fig. 2: model 3 (10 mm between hole pairs), the convergence model, unless figures.domain_model says otherwise
FIGURE2_MODEL = str(
    FIGURE_OPTIONS.get("domain_model", config["study"]["convergence_model"])
)
# instants of Fig. 5 and of Figs. 6-9 (config figures.wave_times, figures.hole_velocity_times; paper §3.4-3.5)
WAVE_TIMES = [float(t) for t in FIGURE_OPTIONS["wave_times"]]
HOLE_TIMES = dict(
    zip(
        ("fig06", "fig07", "fig08", "fig09"),
        (float(t) for t in FIGURE_OPTIONS["hole_velocity_times"]),
    )
)
MODELS_DATASET = paths.dataset(f"models_{STUDY_LEVEL}")
CONVERGENCE_DATASET = paths.dataset("mesh_convergence")


rule fig02_domain:
    input:
        msh=paths.mesh(SYMMETRY, FIGURE2_MODEL, STUDY_LEVEL),
        json=mesh_sidecar(FIGURE2_MODEL, STUDY_LEVEL),
    output:
        figure_outputs("fig02_domain"),
    log:
        paths.log("figures/fig02_domain"),
    params:
        figures=FIGURE_OPTIONS,
        model=FIGURE2_MODEL,
    script:
        "../scripts/plot_figure.py"


rule fig03_mesh_convergence:
    input:
        conv=CONVERGENCE_DATASET,
    output:
        figure_outputs("fig03_mesh_convergence"),
    log:
        paths.log("figures/fig03_mesh_convergence"),
    params:
        figures=FIGURE_OPTIONS,
    script:
        "../scripts/plot_figure.py"


rule fig04_outlet_flow:
    input:
        models=MODELS_DATASET,
    output:
        figure_outputs("fig04_outlet_flow"),
    log:
        paths.log("figures/fig04_outlet_flow"),
    params:
        figures=FIGURE_OPTIONS,
    script:
        "../scripts/plot_figure.py"


rule fig05_wall_displacement:
    input:
        models=MODELS_DATASET,
    output:
        figure_outputs("fig05_wall_displacement"),
    log:
        paths.log("figures/fig05_wall_displacement"),
    params:
        figures=FIGURE_OPTIONS,
        times=WAVE_TIMES,
    script:
        "../scripts/plot_figure.py"


rule fig06_hole_velocity:
    input:
        models=MODELS_DATASET,
    output:
        figure_outputs("fig06_hole_velocity"),
    log:
        paths.log("figures/fig06_hole_velocity"),
    params:
        figures=FIGURE_OPTIONS,
        time=HOLE_TIMES["fig06"],
    script:
        "../scripts/plot_figure.py"


rule fig07_hole_velocity:
    input:
        models=MODELS_DATASET,
    output:
        figure_outputs("fig07_hole_velocity"),
    log:
        paths.log("figures/fig07_hole_velocity"),
    params:
        figures=FIGURE_OPTIONS,
        time=HOLE_TIMES["fig07"],
    script:
        "../scripts/plot_figure.py"


rule fig08_hole_velocity:
    input:
        models=MODELS_DATASET,
    output:
        figure_outputs("fig08_hole_velocity"),
    log:
        paths.log("figures/fig08_hole_velocity"),
    params:
        figures=FIGURE_OPTIONS,
        time=HOLE_TIMES["fig08"],
    script:
        "../scripts/plot_figure.py"


rule fig09_hole_velocity:
    input:
        models=MODELS_DATASET,
    output:
        figure_outputs("fig09_hole_velocity"),
    log:
        paths.log("figures/fig09_hole_velocity"),
    params:
        figures=FIGURE_OPTIONS,
        time=HOLE_TIMES["fig09"],
    script:
        "../scripts/plot_figure.py"


rule fig10_stent_von_mises:
    input:
        models=MODELS_DATASET,
    output:
        figure_outputs("fig10_stent_von_mises"),
    log:
        paths.log("figures/fig10_stent_von_mises"),
    params:
        figures=FIGURE_OPTIONS,
    script:
        "../scripts/plot_figure.py"


rule fig11_hole_flux:
    input:
        models=MODELS_DATASET,
    output:
        figure_outputs("fig11_hole_flux"),
    log:
        paths.log("figures/fig11_hole_flux"),
    params:
        figures=FIGURE_OPTIONS,
    script:
        "../scripts/plot_figure.py"


rule table1:
    input:
        sidecars=[mesh_sidecar(m, STUDY_LEVEL) for m in MODELS],
    output:
        csv=paths.figure("table1", "csv"),
        md=report(
            paths.figure("table1", "md"),
            caption="../report/table1.rst",
            category="Paper figures",
        ),
    log:
        paths.log("figures/table1"),
    params:
        models={m: config["models"][m] for m in MODELS},
    script:
        "../scripts/plot_figure.py"


rule table_gci:
    # Grid Convergence Index of the mesh-convergence study (ureterfsi.analyses.gci; beyond the paper)
    input:
        gci=rules.gci.output[0],
    output:
        csv=paths.figure("table_gci", "csv"),
        md=report(
            paths.figure("table_gci", "md"),
            caption="../report/table_gci.rst",
            category="Mesh convergence",
        ),
    log:
        paths.log("figures/table_gci"),
    script:
        "../scripts/gci.py"


rule all_figures:
    input:
        rules.fig02_domain.output,
        rules.fig03_mesh_convergence.output,
        rules.fig04_outlet_flow.output,
        rules.fig05_wall_displacement.output,
        rules.fig06_hole_velocity.output,
        rules.fig07_hole_velocity.output,
        rules.fig08_hole_velocity.output,
        rules.fig09_hole_velocity.output,
        rules.fig10_stent_von_mises.output,
        rules.fig11_hole_flux.output,
        rules.table1.output,
        *(rules.table_gci.output if len(LEVELS) >= 3 else []),  # the GCI needs three mesh levels
