# Stability at the extremes (issue 5, ureterfsi.stability): one-at-a-time variations of the configuration's
# baseline (config `stability`) on the stent-free r-z model (~1.2k triangles, seconds to minutes per case) and
# the side-hole resolution on a 3D stented model, one-way (minutes per case, the case builds its own mesh); one
# job per case, then the matrix dataset and the stability map. Target: `snakemake --cores 2 stability` (not
# part of `all`).
import json
import re

from ureterfsi.stability import case_by_name, case_setup
from ureterfsi.stability import cases as stability_cases

STABILITY_CASES = [c.name for c in stability_cases(config)] if "stability" in config else []


def stability_mesh(w):
    """The r-z mesh of the case's level (case_setup names a level missing from mesh.levels); none for a
    hole_elements case, whose mesh sizes are its own (built in the case)."""
    s = case_setup(config, case_by_name(config, w.case))
    if s["scene"] == "holes":
        return []
    return f"results/meshes/axisymmetric/model{s['model']}_{s['level']}.msh"


def stability_memory(w):
    """MiB a case reserves: that of a study solve of its scene (solve_mem_mb): r-z fully coupled, or 3D one-way
    at the case's level and symmetry."""
    s = case_setup(config, case_by_name(config, w.case))
    if s["scene"] == "holes":
        return solve_mem_mb("one_way", s["symmetry"], s["level"])
    return solve_mem_mb("fully_coupled", "axisymmetric", s["level"])


def stability_inputs(w):
    """The configuration entering one case (a change re-runs that case; plotting options do not)."""
    case = case_by_name(config, w.case)
    keys = ("geometry", "fluid", "ureter", "stent", "peristalsis", "time", "solver")
    st = {k: v for k, v in config["stability"].items() if k != "axes"}
    s = case_setup(config, case)
    mesh = {"mesh": s["cfg"]["mesh"]} if s["scene"] == "holes" else {}
    return json.dumps({k: config[k] for k in keys} | mesh | {"stability": st, "axis": case.axis, "value": case.value,
                      "model": config["models"][s["model"]]}, sort_keys=True)


if STABILITY_CASES:

    rule stability_case:
        input:
            mesh=stability_mesh,
        output:
            "results/stability/{case}.nc",
        params:
            inputs=stability_inputs,
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
            [report(f"results/figures/stability_map.{ext}", caption="../report/stability_map.rst",
                    category="Stability") if ext == ("png" if "png" in config["figures"]["formats"]
                                                     else config["figures"]["formats"][0])
             else f"results/figures/stability_map.{ext}" for ext in config["figures"]["formats"]],
        params:
            figures=config["figures"],
        log:
            "results/logs/stability/stability_map.log",
        threads: 1
        script:
            "../scripts/stability_map.py"

    rule stability:
        input:
            rules.stability_dataset.output,
            rules.stability_map.output,
