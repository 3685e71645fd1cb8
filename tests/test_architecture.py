"""The structure the architecture promises (docs/architecture.md), checked on the code itself.

* no import cycle between ligwf modules, counting imports inside functions too, and no
  dynamic import (``importlib.import_module`` / ``__import__``) hiding one;
* every module under 400 lines (split by topic before that);
* the study folder's file names appear only in the study model (``ligwf/study/``);
* liquid models are named only inside ``ligwf/liquids/`` (everyone else asks the registry).
"""

from __future__ import annotations

import ast
import re
from pathlib import Path

import networkx as nx
import pytest

from helpers import ROOT

PACKAGE = ROOT / "ligwf"
MAX_LINES = 400


def _module_name(path: Path) -> str:
    parts = path.relative_to(ROOT).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


MODULES = {_module_name(p): p for p in sorted(PACKAGE.rglob("*.py"))}


def _resolve(name: str) -> str | None:
    """The ligwf module an imported name refers to (a module, or a name inside one)."""
    while name:
        if name in MODULES:
            return name
        name = name.rpartition(".")[0]
    return None


def _imports(module: str, path: Path) -> set[str]:
    """ligwf modules imported anywhere in ``path`` (top level and inside functions)."""
    tree = ast.parse(path.read_text(), filename=str(path))
    package = module if path.name == "__init__.py" else module.rpartition(".")[0]
    found: set[str] = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            names = [a.name for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                anchor = package.split(".")[: len(package.split(".")) - node.level + 1]
                base = ".".join(anchor + ([base] if base else []))
            names = [f"{base}.{a.name}" for a in node.names]
        else:
            continue
        for name in names:
            target = _resolve(name)
            if target is not None and target != module:
                found.add(target)
    return found


def import_graph() -> nx.DiGraph:
    g = nx.DiGraph()
    for module, path in MODULES.items():
        g.add_node(module)
        for target in _imports(module, path):
            # a package's __init__ importing its own modules is how a package shows its face
            if not module or not target.startswith(module + ".") or not path.name == "__init__.py":
                g.add_edge(module, target)
    return g


def test_no_import_cycle():
    cycles = list(nx.simple_cycles(import_graph()))
    assert not cycles, "import cycles:\n" + "\n".join(" -> ".join(c + [c[0]]) for c in cycles)


def test_no_dynamic_imports():
    pattern = re.compile(r"\bimport_module\s*\(|__import__\s*\(")
    hits = [f"{p.relative_to(ROOT)}:{n}" for p in MODULES.values()
            for n, line in enumerate(p.read_text().splitlines(), 1) if pattern.search(line)]
    assert not hits, f"dynamic imports hide the dependency graph: {hits}"


@pytest.mark.parametrize("module", sorted(MODULES))
def test_module_is_small(module):
    lines = len(MODULES[module].read_text().splitlines())
    assert lines < MAX_LINES, f"{module}: {lines} lines (split it by topic before {MAX_LINES})"


def _occurrences(pattern: str, allowed: str) -> list[str]:
    rx = re.compile(pattern)
    return [f"{p.relative_to(ROOT)}:{n}: {line.strip()}" for m, p in MODULES.items()
            if not m.startswith(allowed)
            for n, line in enumerate(p.read_text().splitlines(), 1) if rx.search(line)]


def test_study_folder_file_names_only_in_the_study_model():
    hits = _occurrences(r"scene\.json|manifest\.json", "ligwf.study")
    assert not hits, "the study model owns these file names:\n" + "\n".join(hits)


def test_liquid_models_named_only_in_their_modules():
    hits = _occurrences(r"""["'](washino|easo)["']""", "ligwf.liquids")
    assert not hits, "ask ligwf.liquids instead of comparing model names:\n" + "\n".join(hits)


def test_the_checker_sees_function_level_and_relative_imports(tmp_path):
    """The checker itself: an import inside a function and a relative import are edges
    (a cycle cannot hide there)."""
    src = tmp_path / "fake.py"
    src.write_text("from ..engine import site\n\ndef f():\n    from ligwf.cli import main\n")
    assert _imports("ligwf.cli.fake", src) == {"ligwf.engine.site", "ligwf.cli.main"}
