"""ureterfsi.workflow.paths: the one registry of results/ paths (the rules and the package read it)."""
import ast
import re
from pathlib import Path

from ureterfsi.designs.expand import corner_run_paths
from ureterfsi.study.fields import fields_dir
from ureterfsi.workflow import paths

REPO = Path(__file__).resolve().parents[2]


def test_patterns_default_to_the_wildcards_and_fill_them():
    assert paths.mesh() == "results/meshes/{symmetry}/model{model}_{level}.msh"
    assert paths.mesh("quarter", "3", "coarse", "json") == "results/meshes/quarter/model3_coarse.json"
    assert paths.run() == "results/runs/{fidelity}/{symmetry}/model{model}_{level}.nc"
    assert paths.corner_run("s", "c1") == "results/designs/s/rung_check/c1/{corner_rung}.nc"
    assert paths.design_figure(kind="map", ext="png") == "results/figures/designs/{design_study}_map.png"
    assert paths.log("mesh/{symmetry}") == "results/logs/mesh/{symmetry}.log"
    # the field files of a run: its path with runs -> fields
    assert fields_dir(paths.run("one_way", "quarter", "3", "coarse")) == \
        Path("results/fields/one_way/quarter/model3_coarse")
    assert corner_run_paths(type("S", (), {"check": None})()) == {}


def results_literals(text: str) -> list[str]:
    """'line: text' for every string literal of a rule file (or Python source) that spells a results/ path."""
    found = []
    for i, line in enumerate(text.splitlines(), 1):
        code = line.split("#", 1)[0]
        if re.search(r"""["']results/""", code):
            found.append(f"{i}: {line.strip()}")
    return found


results_literals.__test__ = False


def test_no_rule_file_spells_a_results_path():
    planted = 'x = "results/meshes/a.msh"  # ok\n# "results/x"\n'
    assert results_literals(planted) == ['1: x = "results/meshes/a.msh"  # ok']
    found = [f"{f.name}:{hit}" for f in sorted((REPO / "workflow" / "rules").glob("*.smk"))
             for hit in results_literals(f.read_text())]
    assert not found, "results/ paths outside ureterfsi.workflow.paths:\n" + "\n".join(found)


def test_no_package_module_but_paths_spells_a_results_path():
    found = []
    for f in sorted((REPO / "ureterfsi").rglob("*.py")):
        if f.name == "paths.py" and f.parent.name == "workflow":
            continue
        tree = ast.parse(f.read_text())
        docs = {id(n.body[0].value) for n in ast.walk(tree)
                if isinstance(n, (ast.Module, ast.FunctionDef, ast.ClassDef, ast.AsyncFunctionDef))
                and n.body and isinstance(n.body[0], ast.Expr) and isinstance(n.body[0].value, ast.Constant)}
        found += [f"{f.relative_to(REPO)}:{n.lineno}" for n in ast.walk(tree)
                  if isinstance(n, ast.Constant) and isinstance(n.value, str) and id(n) not in docs
                  and n.value.startswith("results/")]
    assert not found, "results/ paths outside ureterfsi.workflow.paths:\n" + "\n".join(found)
