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
            paths.stability_case(),
        log:
            paths.log("stability/{case}"),
        benchmark:
            paths.benchmark("stability/{case}")
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
            cases=expand(paths.stability_case(), case=STABILITY_CASES),
        output:
            nc=paths.dataset("stability"),
            md=paths.dataset("stability_outcomes", "md"),
        log:
            paths.log("stability/dataset"),
        threads: 1
        script:
            "../scripts/stability_dataset.py"

    rule stability_map:
        input:
            paths.dataset("stability"),
        output:
            figure_outputs("stability_map", "Stability"),
        log:
            paths.log("stability/stability_map"),
        threads: 1
        params:
            figures=FIGURE_OPTIONS,
        script:
            "../scripts/stability_map.py"

    rule stability:
        input:
            rules.stability_dataset.output,
            rules.stability_map.output,
