# Figures drawn from the field files of one run (ureterfsi.study.fields, ureterfsi.plotting.fields; beyond the
# paper): the urine flow on the mid-plane around the outlet-most side hole and the wall shear
# stress on the stent around it at the instants of Figs. 6-9, and the urine pressure along the segment at the instants of Fig. 5. The run is the study run of the Fig. 2
# model (figures.domain_model), so the figures cost only their plotting. Target: all_field_figures (in all).

FIELD_MODEL = FIGURE2_MODEL
FIELD_RUN = run_file(FIELD_MODEL, STUDY_LEVEL)
# the field files exist (config fields.enabled) and the model has side holes in a 3D mesh
FIELD_FIGURES = (
    config["fields"]["enabled"]
    and config["models"][FIELD_MODEL]["stent"]
    and run_symmetry(FIELD_MODEL) != "axisymmetric"
)


rule field_hole_flow:
    input:
        run=FIELD_RUN,
    output:
        figure_outputs("field_hole_flow", "Fields"),
    log:
        paths.log("figures/field_hole_flow"),
    params:
        figures=FIGURE_OPTIONS,
        times=list(HOLE_TIMES.values()),
    script:
        "../scripts/field_figures.py"


rule field_pressure:
    input:
        run=FIELD_RUN,
    output:
        figure_outputs("field_pressure", "Fields"),
    log:
        paths.log("figures/field_pressure"),
    params:
        figures=FIGURE_OPTIONS,
        times=WAVE_TIMES,
    script:
        "../scripts/field_figures.py"


rule field_stent_wss:
    input:
        run=FIELD_RUN,
    output:
        figure_outputs("field_stent_wss", "Fields"),
    log:
        paths.log("figures/field_stent_wss"),
    params:
        figures=FIGURE_OPTIONS,
        times=list(HOLE_TIMES.values()),
    script:
        "../scripts/field_figures.py"


rule all_field_figures:
    input:
        rules.field_hole_flow.output if FIELD_FIGURES else [],
        rules.field_stent_wss.output if FIELD_FIGURES else [],
        rules.field_pressure.output if FIELD_FIGURES else [],
