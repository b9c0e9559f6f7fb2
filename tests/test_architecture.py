"""The layout contract: layers whose imports only go down, no import cycles, small modules.

The layers and the forbidden imports are declared once, in ``[tool.importlinter]`` of
``pyproject.toml``; import-linter checks them (including indirect chains between layers).
Cycles between modules are found here from the same import graph.
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import grimp
import pytest
from importlinter.cli import lint_imports

ROOT = Path(__file__).resolve().parents[1]
SRC = ROOT / "src" / "amble"
#: longest source file we accept in the languages without a complexity check here (C, JavaScript,
#: CSS, HTML); vendored libraries aside. Python's limit is its functions' complexity (below).
MAX_LINES = 450


def test_import_contracts_are_kept(monkeypatch):
    monkeypatch.chdir(ROOT)
    assert lint_imports(config_filename=str(ROOT / "pyproject.toml"), no_cache=True, no_logo=True) == 0


def _sccs(graph: dict[str, set[str]]) -> list[list[str]]:
    """Strongly connected components with more than one module (Tarjan, iterative)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on: set[str] = set()
    out: list[list[str]] = []
    counter = 0
    for root in graph:
        if root in index:
            continue
        work = [(root, iter(sorted(graph[root])))]
        index[root] = low[root] = counter
        counter += 1
        stack.append(root)
        on.add(root)
        while work:
            v, it = work[-1]
            w = next(it, None)
            if w is None:
                work.pop()
                if work:
                    low[work[-1][0]] = min(low[work[-1][0]], low[v])
                if low[v] == index[v]:
                    comp = []
                    while True:
                        x = stack.pop()
                        on.discard(x)
                        comp.append(x)
                        if x == v:
                            break
                    if len(comp) > 1:
                        out.append(sorted(comp))
            elif w not in index:
                index[w] = low[w] = counter
                counter += 1
                stack.append(w)
                on.add(w)
                work.append((w, iter(sorted(graph[w]))))
            elif w in on:
                low[v] = min(low[v], index[w])
    return out


def test_no_import_cycles():
    g = grimp.build_graph("amble")
    packages = {m for m in g.modules if g.find_children(m)}
    # a package's __init__ re-exports what lies below it; an import of the package by a module
    # under it is not a dependency between ideas
    graph = {m: {d for d in g.find_modules_directly_imported_by(m) if d not in packages}
             for m in g.modules if m not in packages}
    assert _sccs(graph) == []


def test_cycle_finder_finds_a_cycle():
    assert _sccs({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [["a", "b", "c"]]


def test_no_python_function_is_too_complex():
    """McCabe complexity ≤ 20 per function (``[tool.ruff.lint.mccabe]`` in pyproject.toml)."""
    r = subprocess.run([sys.executable, "-m", "ruff", "check", "--select", "C901", "--output-format", "concise",
                        str(SRC)], cwd=ROOT, capture_output=True, text=True)
    assert r.returncode == 0, r.stdout


@pytest.mark.parametrize("suffix", [".c", ".h", ".js", ".css", ".html"])
def test_no_source_file_is_too_long(suffix):
    long = {str(p.relative_to(SRC)): n for p in SRC.rglob(f"*{suffix}")
            if "_vendor" not in p.parts and not p.name.endswith("_tableau.h")
            for n in [len(p.read_text(errors="ignore").splitlines())] if n > MAX_LINES}
    assert long == {}


#: Public methods of the declaration classes that only read (properties are reads by nature).
_READS = {
    "Names": {"symbol_table", "parse", "domain", "unit", "dot", "symbol"},
    "Actuators": {"input_unit", "input_matrix", "dynamics", "mass_and_bias"},
    "Model": {"dt", "diff", "jacobian", "point_jacobian", "point_velocity", "from_urdf", "constrained", "validate",
              "limit_guards"},
    "HybridSystem": {"footfall_cycle", "check_parameters", "unit", "frame_change", "state_names", "full", "symbolic"},
    "Walker": {"slope_value", "frame_change"},
}


def test_every_method_of_a_declaration_either_reads_or_counts_its_change():
    """A built system is found again by its declarations' revisions: a method that changes a
    declaration without advancing its revision would let a stale build answer for it."""
    import inspect

    from amble.modelling.actuators import Actuators
    from amble.modelling.hybrid import HybridSystem
    from amble.modelling.model import Model
    from amble.modelling.names import Names
    from amble.modelling.walker import Walker

    unmarked = []
    for cls in (Names, Actuators, Model, HybridSystem, Walker):
        for name, f in vars(cls).items():
            if name.startswith("_") or not inspect.isfunction(f):
                continue
            if not getattr(f, "declares", False) and name not in _READS[cls.__name__]:
                unmarked.append(f"{cls.__name__}.{name}")
    assert not unmarked, f"mark these @declaration (they change the declaration) or list them as reads: {unmarked}"


#: Pages about amble's internals (code generation, the cache), which import them by design.
_INTERNALS_PAGES = {"performance.md", "architecture.md"}


def test_readme_docs_and_examples_use_the_public_api_only():
    """What the README, the guides and the examples import is at the package root (or in
    ``amble.models``, ``amble.viz``), so the names a user learns there are the stable ones."""
    import re

    import amble

    root = SRC.parent.parent
    pages = [root / "README.md", *(root / "docs").rglob("*.md"), *(root / "examples").glob("*.py"),
             *(root / "examples").glob("*.ipynb")]
    found, private = set(), []
    for page in pages:
        if page.name in _INTERNALS_PAGES:
            continue
        for mod, names in re.findall(r"from (amble[\w.]*) import ([\w, ]+)", page.read_text()):
            if mod == "amble":
                found |= {n.strip() for n in names.split(",")}
            elif mod not in ("amble.models", "amble.viz") and not mod.startswith("amble.models."):
                private.append(f"{page.name}: from {mod} import {names}")
    assert not private
    assert found <= set(amble.__all__), found - set(amble.__all__)


_RESET_KINDS = {"Impact", "Lock", "Explicit"}


def test_no_module_asks_a_reset_for_its_kind():
    """What a layer does per kind of reset is a ``ResetVisitor`` (one method per kind): a new kind
    is a class and a method in the visitor's base, not an edit of every ``isinstance`` chain."""
    import ast

    asked = []
    for path in SRC.rglob("*.py"):
        if path.name == "transitions.py":
            continue
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.Call) and getattr(node.func, "id", None) in ("isinstance", "issubclass"):
                kinds = node.args[1:2]
                names = {n.id for k in kinds for n in ast.walk(k) if isinstance(n, ast.Name)}
                if names & _RESET_KINDS:
                    asked.append(f"{path.relative_to(SRC)}:{node.lineno}")
    assert not asked
