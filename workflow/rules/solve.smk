# FSI solves (paper §2.2-2.4): one run per model, mesh level and fidelity rung (fully_coupled: the
# monolithic ALE model; one_way: wall -> urine -> stent, serial).
# A run is an MPI job: resources.tasks processes under resources.mpi (mpiexec locally, srun on SLURM).
# A killed run resumes from its checkpoint when Snakemake starts it again (checkpoints are kept outside
# the job's outputs, so Snakemake's clean-up of incomplete outputs does not remove them).
import json
import sys
import tempfile
from types import SimpleNamespace

from ureterfsi.config import run_sections, wall_sections


def solve_command(config, *, model, level, symmetry, fidelity, mesh, out, log, threads, extra="", tasks=1,
                  mpi="mpiexec"):
    """Run `python -m ureterfsi.study` on the whole configuration (handed over as a temporary JSON file);
    fully coupled runs with tasks > 1 go through the MPI launcher, the one-way rung is serial."""
    with tempfile.NamedTemporaryFile("w", suffix=".json", delete=False) as fh:
        json.dump(config, fh)
    launcher = f"{mpi} -n {tasks} " if tasks > 1 and fidelity == "fully_coupled" else ""
    shell(
        f"trap 'rm -f {fh.name}' EXIT; OPENBLAS_NUM_THREADS={threads} {launcher}{sys.executable} -m ureterfsi.study"
        f" --config-json {fh.name} --model {model} --level {level} --symmetry {symmetry} --mesh {mesh}"
        f" --out {out} --fidelity {fidelity} {extra} > {log} 2>&1"
    )


def convergence_only_end(w):
    """Runs that only the mesh-convergence study needs (its model on a level other than study.level) stop at
    study.convergence_time: Fig. 3 and the GCI look no further (the scene models only what it needs)."""
    if w.level != config["study"]["level"] and w.model == str(config["study"]["convergence_model"]):
        return f"--end {config['study']['convergence_time']}"
    return ""


def study_subset(w):
    """The configuration entering one solve (a change re-runs the solve; plotting options do not)."""
    return json.dumps(run_sections(config, w.model), sort_keys=True)


WALL_MOTION = "results/runs/one_way/wall_motion.nc"


rule wall_motion:
    """Step 1 of the one-way rung: the ureter wall alone (r-z) over [0, time.end], once for every one-way run
    (their wall is the same: geometry and load do not depend on the stent model or the 3D mesh)."""
    output:
        WALL_MOTION,
    params:
        wall=lambda w: json.dumps(wall_sections(config), sort_keys=True),
    log:
        "results/logs/solve/one_way/wall_motion.log",
    benchmark:
        "results/benchmarks/solve/one_way/wall_motion.tsv"
    threads: 1
    priority: 10
    resources:
        mem_mb=config["study"]["memory_mb"]["axisymmetric"],
    script:
        "../scripts/wall_motion.py"


def solve_inputs(w):
    """The mesh, and for the one-way rung the shared wall motion."""
    inputs = {"mesh": f"results/meshes/{w.symmetry}/model{w.model}_{w.level}.msh"}
    if w.fidelity == "one_way":
        inputs["wall"] = WALL_MOTION
    return inputs


rule solve:
    input:
        unpack(solve_inputs),
    output:
        "results/runs/{fidelity}/{symmetry}/model{model}_{level}.nc",
    params:
        study=study_subset,
        checkpoint="results/checkpoints/{fidelity}/{symmetry}/model{model}_{level}.npz",
        end=convergence_only_end,
    log:
        "results/logs/solve/{fidelity}/{symmetry}/model{model}_{level}.log",
    benchmark:
        "results/benchmarks/solve/{fidelity}/{symmetry}/model{model}_{level}.tsv"
    threads: 1
    priority: level_priority
    resources:
        tasks=1,
        mpi="mpiexec",
        mem_mb=lambda w: solve_mem_mb(w.fidelity, w.symmetry, w.level),
        runtime=24 * 60,
    run:
        solve_command(config, model=wildcards.model, level=wildcards.level, symmetry=wildcards.symmetry,
                      fidelity=wildcards.fidelity, mesh=input.mesh, out=output[0], log=log[0], threads=threads,
                      extra=f"--checkpoint {params.checkpoint} {params.end}"
                            + (f" --wall {input.wall}" if wildcards.fidelity == "one_way" else ""),
                      tasks=resources.tasks,
                      mpi=resources.mpi)
