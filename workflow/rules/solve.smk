# Fully coupled FSI solves (paper §2.2-2.4): one run per model and mesh level.
# A run is an MPI job: resources.tasks processes under resources.mpi (mpiexec locally, srun on SLURM).
# A killed run resumes from its checkpoint when Snakemake starts it again (checkpoints are kept outside
# the job's outputs, so Snakemake's clean-up of incomplete outputs does not remove them).
import json
import sys


def study_subset(w):
    """The configuration entering one solve (a change re-runs the solve; plotting options do not)."""
    keys = ("geometry", "fluid", "ureter", "stent", "peristalsis", "time", "mesh", "solver")
    return json.dumps({k: config[k] for k in keys} | {"model": config["models"][w.model]}, sort_keys=True)


rule solve:
    input:
        mesh="results/meshes/{symmetry}/model{model}_{level}.msh",
    output:
        "results/runs/{symmetry}/model{model}_{level}.nc",
    params:
        study=study_subset,
        checkpoint="results/checkpoints/{symmetry}/model{model}_{level}.npz",
    log:
        "results/logs/solve/{symmetry}/model{model}_{level}.log",
    benchmark:
        "results/benchmarks/solve/{symmetry}/model{model}_{level}.tsv"
    threads: 1
    resources:
        tasks=1,
        mpi="mpiexec",
        mem_mb=16000,
        runtime=24 * 60,
    run:
        import tempfile

        with tempfile.NamedTemporaryFile("w", suffix=".json", delete=False) as fh:
            json.dump(config, fh)
        launcher = f"{resources.mpi} -n {resources.tasks} " if resources.tasks > 1 else ""
        shell(
            "trap 'rm -f {fh.name}' EXIT; OPENBLAS_NUM_THREADS={threads} {launcher}{sys.executable} -m ureterfsi.study"
            " --config-json {fh.name} --model {wildcards.model} --level {wildcards.level}"
            " --symmetry {wildcards.symmetry} --mesh {input.mesh} --out {output}"
            " --checkpoint {params.checkpoint} > {log} 2>&1"
        )
