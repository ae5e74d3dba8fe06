# Meshes (paper §2.1, §2.4.1): one gmsh .msh + JSON sidecar per symmetry, model and level.


# Stent-free models are also meshed as the axisymmetric r-z section.
AXISYMMETRIC_MODELS = [m for m in MODELS if not config["models"][m]["stent"]]


rule mesh:
    input:
        refuse_unmakeable,
    output:
        msh=paths.mesh(),
        json=paths.mesh(ext="json"),
    log:
        paths.log("mesh/{symmetry}/model{model}_{level}"),
    benchmark:
        paths.benchmark("mesh/{symmetry}/model{model}_{level}")
    priority: solve_priority
    threads: 1
    params:
        # rerun trigger: the configuration entering a mesh
        inputs=lambda w: {k: config[k] for k in ("geometry", "mesh")}
        | {"model": config["models"][w.model]},
    script:
        "../scripts/build_mesh.py"


rule all_meshes:
    input:
        sorted(
            set(
                expand(
                    paths.mesh(ext="{ext}"),
                    symmetry=SYMMETRY,
                    model=MODELS,
                    level=LEVELS,
                    ext=("msh", "json"),
                )
                + expand(
                    paths.mesh("axisymmetric", ext="{ext}"),
                    model=AXISYMMETRIC_MODELS,
                    level=LEVELS,
                    ext=("msh", "json"),
                )
                + [
                    paths.mesh(run_symmetry(m), m, lv, ext)
                    for m in MODELS
                    for lv in LEVELS
                    for ext in ("msh", "json")
                ]
            )
        ),
