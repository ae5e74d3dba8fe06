# Stability at the extremes (ureterfsi.stability): one-at-a-time variations of the configuration's
# baseline (config `stability`) on the stent-free r-z model (~1.2k triangles, seconds to minutes per case) and
# the side-hole resolution on a 3D stented model, one-way (minutes per case, the case builds its own mesh); one
# job per case, then the matrix dataset and the stability map. Target: `snakemake --cores 2 stability` (not
# part of `all`).
import re

if STABILITY_CASES:

    rule stability_case:
        input:
            mesh=stability_mesh,
        output:
            "results/stability/{case}.nc",
        log:
            "results/logs/stability/{case}.log",
        benchmark:
            "results/benchmarks/stability/{case}.tsv"
        wildcard_constraints:
            case="|".join(re.escape(c) for c in STABILITY_CASES),
        threads: 1
        resources:
            mem_mb=stability_memory,
            runtime=90,
        params:
            inputs=stability_inputs,
        script:
            "../scripts/stability_case.py"

    rule stability_dataset:
        input:
            cases=expand("results/stability/{case}.nc", case=STABILITY_CASES),
        output:
            nc="results/datasets/stability.nc",
            md="results/datasets/stability_outcomes.md",
        log:
            "results/logs/stability/dataset.log",
        threads: 1
        script:
            "../scripts/stability_dataset.py"

    rule stability_map:
        input:
            "results/datasets/stability.nc",
        output:
            figure_outputs("stability_map", "Stability"),
        log:
            "results/logs/stability/stability_map.log",
        threads: 1
        params:
            figures=FIGURE_OPTIONS,
        script:
            "../scripts/stability_map.py"

    rule stability:
        input:
            rules.stability_dataset.output,
            rules.stability_map.output,
