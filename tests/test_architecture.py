"""Architecture: no code touches another package's underscore names, and ureterfsi has no import circle (nor
a function-level one) and loads from any of its entry modules.

The private-name scan (AST, no import): an attribute access `x._name` on anything but `self`/`cls`, or a
`from m import _name`, is a violation when `_name` is one of ureterfsi's own underscore names (a method,
attribute, class attribute or module-level name starting with one underscore) and the package of the file
(its directory) defines no such name. Names of other libraries (`np._x`) are not ours to guard.
"""
from __future__ import annotations

import ast
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
SCANNED = ("ureterfsi", "benchmarks", "workflow/scripts")
ENGINE = "ureterfsi/fsi"
# (file, name): a test that deliberately poisons an engine internal
EXEMPT = {
    ("tests/test_fluid_alone.py", "_reaction_ready"),   # forces the reaction to be assembled anew, to compare
    ("tests/test_fluid_alone.py", "_predict"),          # replaced by a predictor that returns NaN
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
FIRST = ("ureterfsi.config", "ureterfsi.config.checks", "ureterfsi.config.validation", "ureterfsi.designs",
         "ureterfsi.stability", "ureterfsi.stability.cases", "ureterfsi.stability.naming")


@pytest.mark.parametrize("module", FIRST)
def test_module_imports_first(module):
    run = subprocess.run([sys.executable, "-c", f"import {module}"], cwd=ROOT, capture_output=True, text=True,
                         timeout=120)
    assert run.returncode == 0, run.stderr[-2000:]
