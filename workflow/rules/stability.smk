# Stability at the extremes (ureterfsi.stability): one-at-a-time variations of the configuration's
# baseline (config `stability`) on the stent-free r-z model (~1.2k triangles, seconds to minutes per case) and
# the side-hole resolution on a 3D stented model, one-way (minutes per case, the case builds its own mesh); one
# job per case, then the matrix dataset and the stability map. Target: `snakemake --cores 2 stability` (not
# part of `all`).
import re

from ureterfsi.stability import jobs as stability_jobs

if STABILITY_CASES:

    rule stability_case:
        input:
            mesh=lambda w: stability_jobs.case_mesh(config, w.case),
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
            mem_mb=lambda w: solve_mem_mb(*stability_jobs.case_rung(config, w.case)),
            runtime=90,
        params:
            inputs=lambda w: stability_jobs.case_trigger(config, w.case),
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
