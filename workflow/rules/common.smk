# Shared helpers of the workflow rules: wildcard constraints and lists derived from the config.

MODELS = sorted(config["models"])
LEVELS = list(config["mesh"]["levels"])
SYMMETRY = config["mesh"]["symmetry"]


wildcard_constraints:
    model="|".join(MODELS),
    level="|".join(LEVELS),
    symmetry="full|half|quarter|axisymmetric",
