"""Architecture: no code touches another package's underscore names, ureterfsi has no import circle (nor
a function-level one) and loads from any of its entry modules, its sub-packages keep their boundaries, and no module
of it is longer than MAX_LINES (unless LONG_MODULES says why it must be); the tests sit in folders of what they
test (never at the top of tests/) and no file under tests/ imports a test file.

The private-name scan (AST, no import): an attribute access `x._name` on anything but `self`/`cls`, or a
`from m import _name`, is a violation when `_name` is one of ureterfsi's own underscore names (a method,
attribute, class attribute or module-level name starting with one underscore) and the package of the file
(its directory) defines no such name. Names of other libraries (`np._x`) are not ours to guard.
"""
from __future__ import annotations

import ast
import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
SCANNED = ("ureterfsi", "benchmarks", "workflow/scripts")
ENGINE = "ureterfsi/fsi"
# (file, name): a test that deliberately poisons an engine internal
EXEMPT = {
    ("tests/fsi/test_fluid_alone.py", "_reaction_ready"),   # forces the reaction to be assembled anew, to compare
    ("tests/fsi/test_fluid_alone.py", "_predict"),          # replaced by a predictor that returns NaN
}


def _private(name: str) -> bool:
    return name.startswith("_") and not name.startswith("__")


def package_of(path: str) -> str:
    """The package a file belongs to: its directory ("ureterfsi/fsi", "tests")."""
    return str(Path(path).parent)


def defined_names(sources: dict) -> dict:
    """{underscore name: set of packages defining it} over {path: source} (methods, self/cls attributes,
    class and module-level names)."""
    out: dict = {}
    for path, src in sources.items():
        for node in ast.walk(ast.parse(src)):
            names = []
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
                names.append(node.name)
            elif isinstance(node, (ast.Assign, ast.AnnAssign, ast.AugAssign)):
                for t in node.targets if isinstance(node, ast.Assign) else [node.target]:
                    for sub in ast.walk(t):
                        if isinstance(sub, ast.Name):
                            names.append(sub.id)
                        elif (isinstance(sub, ast.Attribute) and isinstance(sub.value, ast.Name)
                              and sub.value.id in ("self", "cls")):
                            names.append(sub.attr)
            for name in names:
                if _private(name):
                    out.setdefault(name, set()).add(package_of(path))
    return out


def private_accesses(sources: dict, exempt=frozenset(), owner: str | None = None) -> list[str]:
    """'path:line: name' for every access of another package's underscore name in {path: source} (only
    the names `owner` defines, if given)."""
    owners = defined_names(sources)
    if owner is not None:
        owners = {k: v for k, v in owners.items() if owner in v}
    found = []
    for path, src in sources.items():
        pkg = package_of(path)
        for node in ast.walk(ast.parse(src)):
            if isinstance(node, ast.Attribute):
                own = isinstance(node.value, ast.Name) and node.value.id in ("self", "cls")
                hits = [] if own else [node.attr]
            elif isinstance(node, ast.ImportFrom):
                hits = [a.name for a in node.names]
            else:
                continue
            for name in hits:
                if _private(name) and name in owners and pkg not in owners[name] and (path, name) not in exempt:
                    found.append(f"{path}:{node.lineno}: {name}")
    return found


def module_name(path: str) -> str:
    parts = list(Path(path).with_suffix("").parts)
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def _imports(tree, import_time: bool):
    """The import statements of a module: all of them, or (import_time) those outside functions."""
    if not import_time:
        yield from (n for n in ast.walk(tree) if isinstance(n, (ast.Import, ast.ImportFrom)))
        return
    todo = list(tree.body)
    while todo:
        node = todo.pop()
        if isinstance(node, (ast.Import, ast.ImportFrom)):
            yield node
        elif not isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.Lambda)):
            todo.extend(ast.iter_child_nodes(node))


def import_graph(sources: dict, import_time: bool = False) -> dict:
    """{module: set of the given modules it imports} over {path: source}: every import, or (import_time)
    those run when the module loads; `from pkg import name` points at pkg.name when that is a module."""
    modules = {module_name(p): p for p in sources}
    graph = {}
    for path, src in sources.items():
        me = module_name(path)
        package = me if path.endswith("__init__.py") else me.rpartition(".")[0]
        edges = set()
        for node in _imports(ast.parse(src), import_time):
            if isinstance(node, ast.Import):
                edges |= {a.name for a in node.names}
            elif isinstance(node, ast.ImportFrom):
                base = node.module or ""
                if node.level:
                    anchor = package.split(".")[: len(package.split(".")) - node.level + 1]
                    base = ".".join(anchor + ([base] if base else []))
                edges |= {f"{base}.{a.name}" if f"{base}.{a.name}" in modules else base for a in node.names}
        graph[me] = {m for m in edges if m in modules and m != me}
    return graph


def circles(graph: dict) -> list[set]:
    """The strongly connected components of more than one module (Tarjan): the modules in a circle."""
    index, low, stack, on, out, counter = {}, {}, [], set(), [], [0]

    def visit(v):
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on.add(v)
        for w in sorted(graph.get(v, ())):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                out.append(set(comp))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return out


def cycles(graph: dict) -> list[list[str]]:
    """One cycle (modules, the first repeated at the end) per circle of the graph."""
    return [_cycle_in(graph, comp) for comp in circles(graph)]


def _cycle_in(graph, comp):
    start = min(comp)
    path, seen = [start], {start}
    while True:
        nxt = sorted(w for w in graph[path[-1]] if w in comp)
        back = [w for w in nxt if w == start]
        if back:
            return path + [start]
        w = next((w for w in nxt if w not in seen), nxt[0])
        if w in seen:
            return path[path.index(w):] + [w]
        path.append(w)
        seen.add(w)


def _sources(*dirs) -> dict:
    return {str(p.relative_to(ROOT)): p.read_text() for d in dirs for p in sorted((ROOT / d).rglob("*.py"))
            if ".venv" not in p.parts}


def test_the_scanner_finds_a_private_access_from_another_package():
    sources = {"pkg/engine/core.py": "class Engine:\n    def _assemble(self):\n        self._valid = True\n",
               "pkg/engine/other.py": "def f(e):\n    return e._assemble()\n",
               "pkg/study.py": "def g(e):\n    e._valid = False\n    return e._assemble, e.public, e.__dict__\n",
               "pkg/scripts.py": "from pkg.engine.core import _assemble\nimport numpy as np\nnp._private_lib\n"}
    assert private_accesses(sources) == ["pkg/study.py:2: _valid", "pkg/study.py:3: _assemble",
                                         "pkg/scripts.py:1: _assemble"]
    assert private_accesses(sources, {("pkg/study.py", "_valid")}) == ["pkg/study.py:3: _assemble",
                                                                      "pkg/scripts.py:1: _assemble"]


def test_no_private_member_is_used_outside_its_package():
    found = private_accesses(_sources(*SCANNED), EXEMPT)
    assert not found, "private names used outside their package:\n" + "\n".join(found)


def test_the_cycle_check_finds_a_circle_through_a_function_level_import():
    sources = {"pkg/__init__.py": "", "pkg/a.py": "from . import b\n",
               "pkg/b.py": "def f():\n    from .c import g\n", "pkg/c.py": "from pkg.a import x\n",
               "pkg/d.py": "from .a import y\nimport pkg.b\n"}
    g = import_graph(sources)
    assert g["pkg.a"] == {"pkg.b"} and g["pkg.d"] == {"pkg.a", "pkg.b"}
    assert cycles(g) == [["pkg.a", "pkg.b", "pkg.c", "pkg.a"]]
    assert cycles(import_graph(sources, import_time=True)) == []
    del sources["pkg/c.py"]
    assert cycles(import_graph(sources)) == []


def test_tests_touch_no_private_engine_member():
    found = private_accesses(_sources(ENGINE, "tests"), EXEMPT, owner=ENGINE)
    assert not found, "private engine names used by tests:\n" + "\n".join(found)


def test_ureterfsi_has_no_import_cycle():
    """No circle, function-level imports included: a lazy import does not hide one."""
    found = cycles(import_graph(_sources("ureterfsi")))
    assert not found, "import cycles: " + "; ".join(" -> ".join(c) for c in found)


# modules whose imports reach back into their own packages at import time (config validates design points
# and names stability cases; designs and stability read config): each must load first in a fresh interpreter
FIRST = ("ureterfsi.config", "ureterfsi.config.checks", "ureterfsi.config.study_checks", "ureterfsi.config.validation",
         "ureterfsi.designs.space", "ureterfsi.designs.expand", "ureterfsi.stability", "ureterfsi.stability.cases",
         "ureterfsi.stability.naming")


@pytest.mark.parametrize("module", FIRST)
def test_module_imports_first(module):
    run = subprocess.run([sys.executable, "-c", f"import {module}"], cwd=ROOT, capture_output=True, text=True,
                         timeout=120)
    assert run.returncode == 0, run.stderr[-2000:]


# ---------------------------------------------------------------------------------- sub-package boundaries
# What each sub-package of ureterfsi may import of the others (a sub-package, or one module of it); the package
# itself (`ureterfsi`: REPO_ROOT, the netCDF4-before-dolfinx import order) is open to all. The engine knows no
# ureter; post-processing, data files and figures never reach the solver.
MAY_IMPORT = {
    "analyses": {"data"},
    "config": {"data", "designs", "mesh.geometry", "stability.naming"},
    "data": {"mesh.tags"},
    "designs": {"config", "data", "mesh", "workflow.paths"},
    "fsi": {"data.provenance"},
    "mesh": {"data"},
    "plotting": {"analyses", "data", "designs", "mesh", "stability"},
    "scenes": {"config.end_pressures", "data", "fsi", "mesh"},   # the configured end pressures as functions of time
    "stability": {"config", "data", "fsi", "mesh", "scenes", "study", "workflow.paths"},
    "study": {"config", "data", "fsi", "mesh", "scenes", "workflow.paths"},
    "workflow": {"config", "data"},
}
# sub-packages that never import the solver stack, not even inside a function (figures, tables and checks run
# where dolfinx is not installed or not wanted)
NO_SOLVER = ("analyses", "config", "data", "designs", "plotting", "workflow")
SOLVER_LIBS = {"dolfinx", "ufl", "basix", "ffcx", "petsc4py"}


def _subpackage(module: str) -> str:
    parts = module.split(".")
    return parts[1] if len(parts) > 1 else ""


def boundary_violations(sources: dict) -> list[str]:
    """'module -> module' for every import (function-level ones included) across the sub-package boundaries of
    MAY_IMPORT in {path: source}; a sub-package MAY_IMPORT does not name may import none of the others."""
    found = []
    for me, targets in sorted(import_graph(sources).items()):
        own = _subpackage(me)
        for t in sorted(targets):
            other = _subpackage(t)
            if not other or other == own:
                continue
            allowed = MAY_IMPORT.get(own, set())
            if not any(t == f"ureterfsi.{a}" or t.startswith(f"ureterfsi.{a}.") for a in allowed):
                found.append(f"{me} -> {t}")
    return found


def solver_imports(sources: dict, packages=NO_SOLVER) -> list[str]:
    """'path:line: module' for every import of SOLVER_LIBS in the files of `packages` (ureterfsi/<package>/)."""
    found = []
    for path, src in sources.items():
        if Path(path).parts[:2] not in {("ureterfsi", p) for p in packages}:
            continue
        for node in _imports(ast.parse(src), import_time=False):
            names = [a.name for a in node.names] if isinstance(node, ast.Import) else [node.module or ""]
            found += [f"{path}:{node.lineno}: {n}" for n in names if n.split(".")[0] in SOLVER_LIBS]
    return found


def _docstrings(tree) -> set:
    return {id(n.body[0].value) for n in ast.walk(tree)
            if isinstance(n, (ast.Module, ast.ClassDef, ast.FunctionDef, ast.AsyncFunctionDef)) and n.body
            and isinstance(n.body[0], ast.Expr) and isinstance(n.body[0].value, ast.Constant)}


def test_fixture_paths(sources: dict) -> list[str]:
    """'path:line: text' for every string (docstrings aside) that names the tests/ directory."""
    found = []
    for path, src in sources.items():
        tree = ast.parse(src)
        docs = _docstrings(tree)
        for node in ast.walk(tree):
            if (isinstance(node, ast.Constant) and isinstance(node.value, str) and id(node) not in docs
                    and (node.value == "tests" or node.value.startswith(("tests/", "./tests/")))):
                found.append(f"{path}:{node.lineno}: {node.value}")
    return found


test_fixture_paths.__test__ = False   # a helper, not a test


def test_the_boundary_checks_find_planted_violations():
    sources = {"ureterfsi/__init__.py": "REPO_ROOT = 1\n", "ureterfsi/fsi/__init__.py": "",
               "ureterfsi/fsi/core.py": "from ureterfsi import REPO_ROOT\ndef f():\n    from ureterfsi.mesh import tags\n",
               "ureterfsi/mesh/__init__.py": "", "ureterfsi/mesh/tags.py": "from ureterfsi.data import cf\n",
               "ureterfsi/data/__init__.py": "", "ureterfsi/data/cf.py": "import numpy\n",
               "ureterfsi/analyses/__init__.py": "",
               "ureterfsi/analyses/gci.py": ('"""Reads tests/data/x.yaml."""\nfrom ureterfsi.data import cf\n'
                                             'def f():\n    import dolfinx.fem\n    return "tests/data/x.yaml"\n'),
               "ureterfsi/plotting/__init__.py": "", "ureterfsi/plotting/paper.py": "from ureterfsi.fsi.core import f\n"}
    assert boundary_violations(sources) == ["ureterfsi.fsi.core -> ureterfsi.mesh.tags",
                                            "ureterfsi.plotting.paper -> ureterfsi.fsi.core"]
    assert solver_imports(sources) == ["ureterfsi/analyses/gci.py:4: dolfinx.fem"]
    assert test_fixture_paths(sources) == ["ureterfsi/analyses/gci.py:5: tests/data/x.yaml"]
    sources["ureterfsi/fsi/core.py"] = "from ureterfsi import REPO_ROOT\n"
    sources["ureterfsi/plotting/paper.py"] = "from ureterfsi.analyses import gci\n"
    assert boundary_violations(sources) == []


def test_sub_packages_keep_their_boundaries():
    found = boundary_violations(_sources("ureterfsi"))
    assert not found, "imports across sub-package boundaries (see MAY_IMPORT):\n" + "\n".join(found)


def test_post_processing_data_and_figures_never_import_the_solver():
    found = solver_imports(_sources("ureterfsi"))
    assert not found, "solver imports in " + ", ".join(NO_SOLVER) + ":\n" + "\n".join(found)


def test_the_package_is_sub_packages_with_all_and_listed():
    """ureterfsi/ holds only __init__.py and sub-packages; each sub-package has __all__ and is listed (one line)
    in the package docstring; MAY_IMPORT names every one."""
    pkg = ROOT / "ureterfsi"
    assert sorted(p.name for p in pkg.glob("*.py")) == ["__init__.py"]
    subs = sorted(p.name for p in pkg.iterdir() if (p / "__init__.py").exists())
    doc = ast.get_docstring(ast.parse((pkg / "__init__.py").read_text()))
    listed = {line.split()[0] for line in doc.splitlines() if line[:1].isalpha() and " " in line}
    for sub in subs:
        tree = ast.parse((pkg / sub / "__init__.py").read_text())
        assert any(isinstance(n, ast.Assign) and any(getattr(t, "id", "") == "__all__" for t in n.targets)
                   for n in tree.body), f"ureterfsi/{sub}/__init__.py: no __all__"
        assert sub in listed, f"ureterfsi/__init__.py's docstring does not list {sub}"
    assert sorted(MAY_IMPORT) == subs


def test_no_module_reads_the_tests_directory():
    found = test_fixture_paths(_sources("ureterfsi"))
    assert not found, "ureterfsi reads test fixtures:\n" + "\n".join(found)


def test_layout_violations(sources: dict) -> list[str]:
    """'path: ...' for every test file at the top level of tests/ (tests sit in the folder of what they test), and
    every import of a test module (a module named test_*) from any file under tests/ (shared code lives in
    tests/helpers or a conftest.py, never in another test file)."""
    found = []
    for path, src in sources.items():
        parts = Path(path).parts
        if len(parts) == 2 and parts[1].startswith("test_"):
            found.append(f"{path}: a test file at the top level of tests/")
        for node in _imports(ast.parse(src), import_time=False):
            if isinstance(node, ast.Import):
                names = [a.name for a in node.names]
            else:
                module = "." * node.level + (node.module or "")
                names = [module] if _names_a_test(module) else [module.rstrip(".") + "." + a.name for a in node.names]
            found += [f"{path}:{node.lineno}: imports {n}" for n in names if _names_a_test(n)]
    return sorted(found)


def _names_a_test(module: str) -> bool:
    return any(part.startswith("test_") for part in module.split("."))


test_layout_violations.__test__ = False   # a helper, not a test


def test_the_layout_check_finds_planted_violations():
    sources = {"tests/test_loose.py": "", "tests/conftest.py": "",
               "tests/analyses/test_gci.py": "def f():\n    from test_aggregate_figures import synthetic_run\n",
               "tests/data/test_cf.py": "import analyses.test_gci as g\n",
               "tests/designs/test_designs.py": "from . import test_other\n",
               "tests/helpers/synthetic.py": "from helpers.compare import assert_same_arithmetic\n",
               "tests/fsi/test_mpi.py": "from helpers.engine_cases import tube_problem\n"}
    assert test_layout_violations(sources) == ["tests/analyses/test_gci.py:2: imports test_aggregate_figures",
                                               "tests/data/test_cf.py:1: imports analyses.test_gci",
                                               "tests/designs/test_designs.py:1: imports .test_other",
                                               "tests/test_loose.py: a test file at the top level of tests/"]


def test_tests_mirror_the_package_and_import_no_test_file():
    found = test_layout_violations(_sources("tests"))
    assert not found, "tests/ layout:\n" + "\n".join(found)


def test_no_text_names_a_stop_number():
    """No tracked file (docs/ aside: their own rewrite) says "stop NN" (the project's text speaks of the project)."""
    files = subprocess.run(["git", "ls-files"], cwd=ROOT, capture_output=True, text=True, check=True).stdout.split()
    stop = re.compile(r"\bstop \d+", re.I)
    found = []
    for f in files:
        if f.startswith("docs/") or not (ROOT / f).is_file():
            continue
        try:
            text = (ROOT / f).read_text()
        except UnicodeDecodeError:
            continue
        found += [f"{f}:{i}" for i, line in enumerate(text.splitlines(), 1) if stop.search(line)]
    assert not found, '"stop NN" in:\n' + "\n".join(found)


# ---------------------------------------------------------------------------------------------- module length
MAX_LINES = 450
# modules allowed above MAX_LINES: {path: why it must be one module}; each entry must still be needed
LONG_MODULES: dict[str, str] = {}


def long_modules(sources: dict, limit: int = MAX_LINES, exempt: dict = LONG_MODULES) -> list[str]:
    """'path: N lines' for every module of {path: source} longer than `limit` lines and not in `exempt`."""
    lengths = {path: len(src.splitlines()) for path, src in sorted(sources.items())}
    return [f"{path}: {n} lines" for path, n in lengths.items() if n > limit and path not in exempt]


def test_the_length_check_finds_a_long_module():
    sources = {"ureterfsi/fsi/core.py": "x = 1\n" * 451, "ureterfsi/fsi/short.py": "x = 1\n" * 450,
               "ureterfsi/data/table.py": "x = 1\n" * 600}
    assert long_modules(sources, exempt={}) == ["ureterfsi/data/table.py: 600 lines",
                                                "ureterfsi/fsi/core.py: 451 lines"]
    assert long_modules(sources, exempt={"ureterfsi/data/table.py": "a table"}) == ["ureterfsi/fsi/core.py: 451 lines"]


def test_no_module_is_longer_than_the_limit():
    sources = _sources("ureterfsi")
    found = long_modules(sources)
    assert not found, f"modules above {MAX_LINES} lines (split them by concern, or justify in LONG_MODULES):\n" \
        + "\n".join(found)
    stale = [p for p in LONG_MODULES if p not in sources or len(sources[p].splitlines()) <= MAX_LINES]
    assert not stale, f"LONG_MODULES lists modules within {MAX_LINES} lines or gone: {stale}"
