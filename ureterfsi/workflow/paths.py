"""Every results/ path of the workflow, one function per kind of file. Each argument defaults to the Snakemake
wildcard of its name, so ``mesh()`` is the mesh rule's output pattern and ``mesh("quarter", "3", "coarse")`` one
file; the rules (workflow/rules/*.smk) and the package read their paths here."""

RESULTS = "results"


def _w(name: str) -> str:
    return "{" + name + "}"


def mesh(symmetry=_w("symmetry"), model=_w("model"), level=_w("level"), ext="msh") -> str:
    """A stent model's gmsh mesh on one level and symmetry (.msh), or its sidecar (ext json)."""
    return f"{RESULTS}/meshes/{symmetry}/model{model}_{level}.{ext}"


def run_config(fidelity=_w("fidelity"), model=_w("model")) -> str:
    """The configuration of a model's solves on one fidelity rung (config.run_sections as JSON)."""
    return f"{RESULTS}/configs/{fidelity}/model{model}.json"


def run(fidelity=_w("fidelity"), symmetry=_w("symmetry"), model=_w("model"), level=_w("level")) -> str:
    """One study solve's run file."""
    return f"{RESULTS}/runs/{fidelity}/{symmetry}/model{model}_{level}.nc"


WALL_MOTION = f"{RESULTS}/runs/one_way/wall_motion.nc"   # the r-z wall motion every one-way run shares
RUNS, FIELDS = "runs", "fields"                          # a run's field files: its path with runs -> fields
CALIBRATION = f"{RESULTS}/calibration/wall_calibration.json"


def checkpoint(name: str) -> str:
    """A solve's restart checkpoint (name as its run's, relative to its folder)."""
    return f"{RESULTS}/checkpoints/{name}.npz"


def dataset(name: str, ext: str = "nc") -> str:
    """A dataset of the study (models, mesh convergence, GCI, ladder, stability)."""
    return f"{RESULTS}/datasets/{name}.{ext}"


def figure(name: str, ext: str) -> str:
    """A figure or table file."""
    return f"{RESULTS}/figures/{name}.{ext}"


def log(name: str) -> str:
    """A rule's log."""
    return f"{RESULTS}/logs/{name}.log"


def benchmark(name: str) -> str:
    """A rule's benchmark (time and memory)."""
    return f"{RESULTS}/benchmarks/{name}.tsv"


def ladder_run(rung=_w("rung")) -> str:
    """A fidelity-ladder rung's run file."""
    return f"{RESULTS}/ladder/{rung}.nc"


STABILITY = f"{RESULTS}/stability"


def stability_case(case=_w("case")) -> str:
    """A stability case's run file."""
    return f"{STABILITY}/{case}.nc"


DESIGNS = f"{RESULTS}/designs"


def design_mesh(mesh_id=_w("mesh_id"), ext="msh") -> str:
    """A design mesh (shared by the points and corners of the same mesh configuration), or its sidecar."""
    return f"{DESIGNS}/meshes/{mesh_id}.{ext}"


def design_wall_motion(wall_id=_w("wall_id")) -> str:
    """A design's r-z wall motion (one-way rung)."""
    return f"{DESIGNS}/wall_motion/{wall_id}.nc"


def design_run(study=_w("design_study"), point=_w("point")) -> str:
    """A design point's run file."""
    return f"{DESIGNS}/{study}/{point}/run.nc"


def escalated_run(study=_w("design_study"), point=_w("point")) -> str:
    """A design point's fully coupled run file, where its study's rung check escalated it."""
    return f"{DESIGNS}/{study}/{point}/fully_coupled.nc"


def corner_run(study=_w("design_study"), corner=_w("corner"), rung=_w("corner_rung")) -> str:
    """A rung-check corner's run file on one rung."""
    return f"{DESIGNS}/{study}/rung_check/{corner}/{rung}.nc"


def rung_check(study=_w("design_study")) -> str:
    """A design study's rung check (the rung error per corner and quantity)."""
    return f"{DESIGNS}/{study}/rung_check.nc"


def design_dataset(study=_w("design_study")) -> str:
    """A design study's dataset."""
    return f"{DESIGNS}/{study}.nc"


def design_question() -> str:
    """The spacing's effect on the outlet flow over every study that varies it (ureterfsi.designs.question)."""
    return f"{DESIGNS}/question.md"


def design_figure(study=_w("design_study"), kind=_w("kind"), ext=_w("ext")) -> str:
    """A design study's figure of one kind."""
    return figure(f"designs/{study}_{kind}", ext)


def design_field_figure(study=_w("design_study"), point=_w("point"), kind=_w("kind"), ext=_w("ext")) -> str:
    """A field figure (ureterfsi.plotting.fields.run_field_figure kind) of one design point."""
    return figure(f"designs/{study}_{point}_{kind}", ext)
