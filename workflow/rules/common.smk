# Shared helpers of the workflow rules: wildcard constraints and lists derived from the config.
import sys

from ureterfsi.config import unmakeable

MODELS = sorted(config["models"])
LEVELS = list(config["mesh"]["levels"])
SYMMETRY = config["mesh"]["symmetry"]
FIDELITY = config["study"]["fidelity"]


def run_symmetry(model):
    """Mesh symmetry of a model's study runs: mesh.symmetry unless study.runs overrides it."""
    return config["study"]["runs"].get(str(model), {}).get("symmetry", SYMMETRY)


def run_fidelity(model):
    """Fidelity rung of a model's study runs: study.fidelity unless study.runs overrides it."""
    return config["study"]["runs"].get(str(model), {}).get("fidelity", FIDELITY)


def local_memory_budget_mb(headroom_mb):
    """Physical memory of this machine (MemTotal of /proc/meminfo) less a headroom for the OS, MiB."""
    with open("/proc/meminfo") as fh:
        total_kib = next(int(line.split()[1]) for line in fh if line.startswith("MemTotal:"))
    return total_kib // 1024 - int(headroom_mb)


# Memory budget of local runs. Solves reserve mem_mb (study.memory_mb), but Snakemake holds reservations only
# against a global `--resources mem_mb=...`, which the command line or a profile sets - and the workflow profile
# under workflow/profiles/ is not searched when the Snakefile sits at the repository root. Without a budget a
# plain `snakemake --cores 2` started the fine and medium runs side by side (15.6 + 8.8 GiB on 24 GiB). So
# unless one is given, a local run budgets the machine's memory less study.memory_headroom_mb.
if workflow.local_exec and "mem_mb" not in workflow.global_resources:
    workflow.register_resource("mem_mb", local_memory_budget_mb(config["study"]["memory_headroom_mb"]))


def level_priority(w):
    """Scheduling priority of a level's mesh and solve jobs: finer levels first (longest job first: the fine
    run of the mesh study is the critical path of the default reproduction: it starts as soon as its mesh exists
    and the memory budget allows, and the coarse runs fill the other core around it)."""
    factors = sorted({float(v["size_factor"]) for v in config["mesh"]["levels"].values()}, reverse=True)
    return factors.index(float(config["mesh"]["levels"][w.level]["size_factor"]))


def solve_mem_mb(fidelity, symmetry, level):
    """MiB a solve reserves (resource mem_mb) from study.memory_mb: r-z runs reserve `axisymmetric`, 3D runs
    their fidelity's entry for the level (a level without one: that fidelity's largest entry; the entries are
    for quarter meshes) times the symmetry's factor."""
    table = config["study"]["memory_mb"]
    if symmetry == "axisymmetric":
        return int(table["axisymmetric"])
    per_level = table[fidelity]
    return int(per_level.get(level, max(per_level.values())) * table["symmetry_factor"][symmetry])


def refuse_unmakeable(w):
    """Input function (no input) of rule mesh: a mesh the configuration cannot make, and so every run on it, is
    refused before any job starts, in one line on stderr (an exception here would print a traceback)."""
    reason = unmakeable(config, w.model, w.level, w.symmetry)
    if reason:
        sys.stderr.write(f"target error: results/meshes/{w.symmetry}/model{w.model}_{w.level}.msh: {reason}\n")
        sys.exit(2)
    return []


# model and level as the schema spells them (not only the configured ones): refuse_unmakeable names the reason
wildcard_constraints:
    model="[1-9][0-9]*",
    level="[A-Za-z][A-Za-z0-9_]*",
    symmetry="full|half|quarter|axisymmetric",
    fidelity="fully_coupled|one_way",
