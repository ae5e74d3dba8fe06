# Shared helpers of the workflow rules: wildcard constraints and lists derived from the config.

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


wildcard_constraints:
    model="|".join(MODELS),
    level="|".join(LEVELS),
    symmetry="full|half|quarter|axisymmetric",
    fidelity="fully_coupled|one_way",
