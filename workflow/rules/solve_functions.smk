# Input functions, params and resources of the solve and ladder stages (solve.smk, ladder.smk), thin
# wrappers of the package; included after common.smk.
from ureterfsi.config import one_way_unposable

# solve: a study run


def run_config_file(fidelity, model):
    """The configuration file of a model's solves on a rung: config.run_sections as JSON, written by rule
    solve_config."""
    return paths.run_config(fidelity, model)


def study_rung(w):
    """(fidelity, symmetry, level) of a study solve: its wildcards."""
    return w.fidelity, w.symmetry, w.level


def solve_inputs(w):
    """The mesh and the configuration file, and for the one-way rung the shared wall motion."""
    inputs = {
        "mesh": paths.mesh(w.symmetry, w.model, w.level),
        "config": run_config_file(w.fidelity, w.model),
    }
    if w.fidelity == "one_way":
        if one_way_unposable(config):  # refused before any job starts, in one line
            sys.stderr.write(
                f"target error: {paths.run('one_way', w.symmetry, w.model, w.level)}: "
                f"{one_way_unposable(config)}\n"
            )
            sys.exit(2)
        inputs["wall"] = paths.WALL_MOTION
    return inputs


def convergence_end(w):
    """Runs that only the mesh-convergence study needs (its model on a level other than study.level) stop at
    study.convergence_time: Fig. 3 and the GCI look no further (the scene models only what it needs). None: the
    run's time.end.
    """
    if w.level != STUDY_LEVEL and w.model == CONVERGENCE_MODEL:
        return config["study"]["convergence_time"]
    return None


def convergence_only_end(w):
    """Params end (a rerun trigger): convergence_end as the command spells it."""
    end = convergence_end(w)
    return "" if end is None else f"--end {end}"


def study_job(w, input, output):
    """The solve of one study run (launch.SolveJob)."""
    return launch.SolveJob(
        w.fidelity,
        w.symmetry,
        w.model,
        w.level,
        input.mesh,
        output[0],
        paths.checkpoint(f"{w.fidelity}/{w.symmetry}/model{w.model}_{w.level}"),
        run_config=input.config,
        wall=input.get("wall"),
        end=convergence_end(w),
    )


# ladder_run: a fidelity-ladder rung (config ladder)


def ladder_rung(w):
    """(fidelity, symmetry, level) of a ladder rung (config ladder.rungs)."""
    rung = LADDER_RUNGS[w.rung]
    return rung["fidelity"], rung["symmetry"], rung["level"]


def ladder_job(w, input, output):
    """The solve of a ladder rung (launch.SolveJob) over [0, ladder.end] at the rung's time step."""
    rung = LADDER_RUNGS[w.rung]
    return launch.SolveJob(
        rung["fidelity"],
        rung["symmetry"],
        str(LADDER["model"]),
        rung["level"],
        input.mesh,
        output[0],
        paths.checkpoint(f"ladder/{w.rung}"),
        run_config=input.config,
        end=LADDER["end"],
        dt=rung["dt"],
    )
