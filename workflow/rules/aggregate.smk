# Study datasets (paper §3): the per-run probe files combined across stent models (one mesh level) and
# across mesh levels (mesh-convergence study, paper §3.1). ureterfsi.aggregate reads model, level and
# symmetry from each file's attributes; the rules only choose which runs enter.

STUDY_LEVEL = config["study"]["level"]
CONVERGENCE_MODEL = str(config["study"]["convergence_model"])


def run_file(model, level):
    """Per-run probe dataset of one stent model on one mesh level (written by the solve rule), at the
    model's fidelity rung and mesh symmetry (study.fidelity, mesh.symmetry, study.runs)."""
    return f"results/runs/{run_fidelity(model)}/{run_symmetry(model)}/model{model}_{level}.nc"


def mesh_sidecar(model, level):
    """JSON sidecar of the mesh of one stent model on one mesh level (the mesh its study runs use)."""
    return f"results/meshes/{run_symmetry(model)}/model{model}_{level}.json"


rule aggregate_models:
    input:
        runs=lambda w: [run_file(m, w.level) for m in MODELS],
    output:
        "results/datasets/models_{level}.nc",
    params:
        # rerun triggers: the Table 1 labels stored in the dataset and the time-grid choice
        labels={m: config["models"][m]["label"] for m in MODELS},
        time_grid="union",
    log:
        "results/logs/aggregate/models_{level}.log",
    threads: 1
    script:
        "../scripts/aggregate_models.py"


rule aggregate_convergence:
    input:
        runs=[run_file(CONVERGENCE_MODEL, lv) for lv in LEVELS],
    output:
        "results/datasets/mesh_convergence.nc",
    params:
        time=config["study"]["convergence_time"],
        levels=LEVELS,
    log:
        "results/logs/aggregate/mesh_convergence.log",
    threads: 1
    script:
        "../scripts/aggregate_convergence.py"


# Grid Convergence Index (Celik et al. 2008) of the mesh-convergence study: peak outlet flux, peak maximum
# stent von Mises stress and the probe-line stress at GCI_POINTS_Z, from the three finest levels
# (ureterfsi.gci). h = (V/N)^(1/3) with V the analytic volume of the mesh (the same on every level; read from
# the last level's mesh sidecar). Needs at least three mesh levels (all_figures asks for it only then).
# probe-line points: a quarter, half and three quarters of the segment (12.5, 25, 37.5 mm for L = 50 mm)
GCI_POINTS_Z = [round(f * float(config["geometry"]["length"]), 9) for f in (0.25, 0.5, 0.75)]
GCI_SAFETY_FACTOR = 1.25                 # Celik et al. 2008, three grids


rule gci:
    input:
        conv="results/datasets/mesh_convergence.nc",
        mesh=mesh_sidecar(CONVERGENCE_MODEL, LEVELS[-1]),
    output:
        "results/datasets/mesh_convergence_gci.nc",
    params:
        points_z=GCI_POINTS_Z,
        safety_factor=GCI_SAFETY_FACTOR,
    log:
        "results/logs/aggregate/mesh_convergence_gci.log",
    threads: 1
    script:
        "../scripts/gci.py"
