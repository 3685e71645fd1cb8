"""Seams, not shims: the module boundaries are real, checked on the code itself.

* no private name (a leading underscore) crosses a module: nothing of ligwf imports
  ``_name`` from another module or reads ``module._name`` of a ligwf module it imported;
* no re-export shim: a name imported from a ligwf module (in ligwf/, tests/, benchmarks/,
  scripts/) is defined there, not passed on from elsewhere (a package's ``__init__``, its
  face, may hand names on), and no ``# noqa: F401`` keeps an unused import alive in ligwf/;
* no dead function, method or class in ligwf/: vulture, reading ligwf/ with the tests,
  benchmarks and scripts that call it, finds none; the true entry points it cannot see
  (called by Python itself) are named in ``tests/dead_code_whitelist.py``.

Each checker is first shown to see what it looks for, on a small source of its own.
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest
from vulture import Vulture

from helpers import ROOT

PACKAGE = ROOT / "ligwf"
#: where callers of ligwf live (their imports must name the defining module too)
CALLERS = ("ligwf", "tests", "benchmarks", "scripts")
WHITELIST = ROOT / "tests" / "dead_code_whitelist.py"


def _module_name(path: Path, root: Path = ROOT) -> str:
    parts = path.relative_to(root).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


MODULES = {_module_name(p): p for p in sorted(PACKAGE.rglob("*.py"))}


def _absolute(node: ast.ImportFrom, module: str, is_package: bool) -> str:
    """The absolute module name of a (possibly relative) ``from ... import``."""
    if not node.level:
        return node.module or ""
    package = module if is_package else module.rpartition(".")[0]
    anchor = package.split(".")[: len(package.split(".")) - node.level + 1]
    return ".".join(anchor + ([node.module] if node.module else []))


def defined_names(tree: ast.Module) -> set[str]:
    """Names a module defines at its top level (under ``if`` / ``try`` too): functions,
    classes and assigned names; imported names are not defined there."""
    found: set[str] = set()
    todo = list(tree.body)
    while todo:
        node = todo.pop()
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
            found.add(node.name)
        elif isinstance(node, (ast.Assign, ast.AnnAssign, ast.AugAssign)):
            targets = node.targets if isinstance(node, ast.Assign) else [node.target]
            found.update(n.id for t in targets for n in ast.walk(t) if isinstance(n, ast.Name))
        elif isinstance(node, (ast.If, ast.Try)):
            todo.extend([*node.body, *node.orelse, *getattr(node, "finalbody", []),
                         *(b for h in getattr(node, "handlers", []) for b in h.body)])
    return found


DEFINED = {m: defined_names(ast.parse(p.read_text())) for m, p in MODULES.items()}


def private_crossings(module: str, path: Path) -> list[str]:
    """Every private name of another ligwf module that ``path`` imports or reads."""
    tree = ast.parse(path.read_text())
    is_package = path.name == "__init__.py"
    found, aliases = [], {}
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom):
            source = _absolute(node, module, is_package)
            for a in node.names:
                if f"{source}.{a.name}" in MODULES:
                    aliases[a.asname or a.name] = f"{source}.{a.name}"
                elif a.name.startswith("_") and not a.name.startswith("__") \
                        and source.startswith("ligwf") and source != module:
                    found.append(f"{path.name}:{node.lineno}: from {source} import {a.name}")
        elif isinstance(node, ast.Import):
            for a in node.names:
                if a.name in MODULES and a.asname:
                    aliases[a.asname] = a.name
    for node in ast.walk(tree):
        if (isinstance(node, ast.Attribute) and node.attr.startswith("_")
                and not node.attr.startswith("__")):
            owner = (aliases.get(node.value.id) if isinstance(node.value, ast.Name)
                     else ast.unparse(node.value) if ast.unparse(node.value) in MODULES
                     else None)
            if owner is not None and owner != module:
                found.append(f"{path.name}:{node.lineno}: {ast.unparse(node)}")
    return found


def shims_used(path: Path, module: str = "") -> list[str]:
    """Every ``from ligwf.x import name`` in ``path`` where module ``x`` (not a package's
    ``__init__``) does not define ``name`` (it only passes on an import)."""
    tree = ast.parse(path.read_text())
    found = []
    for node in ast.walk(tree):
        if not isinstance(node, ast.ImportFrom):
            continue
        source = _absolute(node, module, path.name == "__init__.py")
        if source not in MODULES or MODULES[source].name == "__init__.py":
            continue
        for a in node.names:
            if a.name not in DEFINED[source] and f"{source}.{a.name}" not in MODULES:
                found.append(f"{path.relative_to(ROOT) if path.is_relative_to(ROOT) else path}"
                             f":{node.lineno}: {a.name} from {source}, which does not define it")
    return found


def dead_code(paths: list[Path], package: Path = PACKAGE,
              whitelist: Path | None = WHITELIST) -> list[str]:
    """Functions, methods and classes in ``package`` that no code of ``paths`` uses
    (vulture, 60 % confidence), and anything there vulture is sure of (100 %)."""
    v = Vulture(ignore_decorators=["@model_validator", "@field_validator", "@model_serializer",
                                   "@pytest.fixture"])
    v.scavenge([str(p) for p in paths] + ([str(whitelist)] if whitelist else []))
    return [f"{item.filename}:{item.first_lineno}: unused {item.typ} {item.name!r} "
            f"({item.confidence} %)" for item in v.get_unused_code(min_confidence=60)
            if Path(item.filename).resolve().is_relative_to(package.resolve())
            and (item.typ in ("function", "method", "class") or item.confidence == 100)]


# ---- the checkers see what they look for

def test_the_private_name_check_sees_imports_and_module_attributes(tmp_path):
    src = tmp_path / "fake.py"
    src.write_text("from ligwf.engine.cores import at_least, _hidden\n"
                   "from ligwf.engine import thermo\nimport ligwf.engine.site as site\n"
                   "x = thermo._PRIVATE, site._version_line, thermo.LOOP_RE, thermo.__doc__\n")
    found = private_crossings("ligwf.report.fake", src)
    assert [f.split(": ", 1)[1] for f in found] == [
        "from ligwf.engine.cores import _hidden", "thermo._PRIVATE", "site._version_line"]


def test_the_shim_check_sees_a_name_passed_on(tmp_path):
    src = tmp_path / "fake.py"
    src.write_text("from ligwf.engine.plan import at_least, case_load\n"
                   "from ligwf.api import open_study\n")     # a package's face may hand on
    found = shims_used(src, "ligwf.report.fake")
    assert len(found) == 1 and "at_least from ligwf.engine.plan" in found[0]


def test_the_dead_code_check_sees_an_uncalled_function(tmp_path):
    package, caller = tmp_path / "pkg", tmp_path / "caller.py"
    package.mkdir()
    (package / "mod.py").write_text("def never_called():\n    return 1\n\n\n"
                                    "def called():\n    return 2\n\n\n"
                                    "class Entry:\n    pass\n")
    caller.write_text("from pkg.mod import called\n\ncalled()\n")
    whitelist = tmp_path / "whitelist.py"
    whitelist.write_text("Entry\n")
    found = dead_code([package, caller], package, whitelist)
    assert [f.split(": ", 1)[1] for f in found] == ["unused function 'never_called' (60 %)"]
    found = dead_code([package, caller], package, whitelist=None)
    assert {f.split(": ", 1)[1] for f in found} == {"unused function 'never_called' (60 %)",
                                                    "unused class 'Entry' (60 %)"}


# ---- the rules

@pytest.mark.parametrize("module", sorted(MODULES))
def test_no_private_name_crosses_a_module(module):
    found = private_crossings(module, MODULES[module])
    assert not found, (f"{module} uses private names of other modules (make the name public "
                       "in the module that defines it, or move the code there):\n"
                       + "\n".join(found))


def test_no_reexport_shim():
    noqa = [f"{p.relative_to(ROOT)}:{n}" for p in MODULES.values()
            for n, line in enumerate(p.read_text().splitlines(), 1) if "noqa: F401" in line]
    assert not noqa, f"imports kept only to be passed on (import from the defining module): {noqa}"
    found = [hit for folder in CALLERS for p in sorted((ROOT / folder).rglob("*.py"))
             for hit in shims_used(p, _module_name(p) if folder == "ligwf" else "")]
    assert not found, "import these from the module that defines them:\n" + "\n".join(found)


def test_no_dead_function_in_ligwf():
    found = dead_code([ROOT / folder for folder in CALLERS])
    assert not found, ("nothing calls these (remove them, or name a true entry point in "
                       "tests/dead_code_whitelist.py):\n" + "\n".join(found))
