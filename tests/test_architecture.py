"""The structure the architecture promises (docs/architecture.md), checked on the code itself.

* the packages form layers that point one way (:data:`LAYERS`, bottom first): a module
  imports only modules of its own layer or of layers below it, counting imports inside
  functions and under ``TYPE_CHECKING`` too; every module belongs to exactly one layer;
* inside the analysis stage the sub-packages form layers too (:data:`ANALYSIS_LAYERS`:
  kernels, frames, records, flow, granules, GSD, the granule stage, the runners);
* no import cycle between ligwf modules, counting imports inside functions too, and no
  dynamic import (``importlib.import_module`` / ``__import__``) hiding one;
* the study folder's file names appear only in the study model (``ligwf/study/``);
* liquid models are named only inside ``ligwf/liquids/`` (everyone else asks the registry).

No line count: a module is split where its concept divides, and the seams are what is
checked (here the layers; tests/test_seams.py: no private name crossing a module, no
re-export shim, no dead code). A cap of 400 lines was here until issue 48: modules were cut
and docstrings shortened to meet it, which no seam asked for.
"""

from __future__ import annotations

import ast
import re
from pathlib import Path

import networkx as nx

from helpers import ROOT

PACKAGE = ROOT / "ligwf"


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


#: The layers, bottom first: each lists the packages / modules it holds (a name covers the
#: modules below it). A module may import its own layer and the layers below, never above.
LAYERS: tuple[tuple[str, tuple[str, ...]], ...] = (
    ("base", ("ligwf", "ligwf.errors", "ligwf.fsio", "ligwf.yamlio", "ligwf.numba_cache")),
    ("liquids", ("ligwf.liquids",)),
    ("scene", ("ligwf.scene",)),
    ("folder model", ("ligwf.study",)),
    ("engine", ("ligwf.engine",)),
    ("analysis", ("ligwf.analysis",)),
    ("inference", ("ligwf.inference",)),
    ("report", ("ligwf.report",)),
    ("executors", ("ligwf.eligibility", "ligwf.scheduler", "ligwf.local", "ligwf.slurm",
                   "ligwf.executors")),
    ("pipeline", ("ligwf.pipeline",)),
    ("cli", ("ligwf.cli", "ligwf.__main__")),
    ("api", ("ligwf.api",)),
)


def layer_of(module: str, layers=LAYERS) -> int | None:
    """Index in ``layers`` of the layer holding ``module`` (the longest matching name)."""
    best, length = None, -1
    for number, (_, names) in enumerate(layers):
        for name in names:
            covers = module == name or (name != "ligwf" and module.startswith(name + "."))
            if covers and len(name) > length:
                best, length = number, len(name)
    return best


def up_edges(graph: nx.DiGraph, layers=LAYERS) -> list[str]:
    """Every import from a layer into a layer above it, as ``a -> b (layer < layer)``."""
    found = []
    for a, b in sorted(graph.edges()):
        la, lb = layer_of(a, layers), layer_of(b, layers)
        if la is not None and lb is not None and lb > la:
            found.append(f"{a} -> {b} ({layers[la][0]} imports {layers[lb][0]})")
    return found


def test_every_module_has_a_layer():
    homeless = [m for m in MODULES if layer_of(m) is None]
    assert not homeless, f"modules in no layer (add them to LAYERS): {homeless}"


def test_layers_point_one_way():
    edges = up_edges(import_graph())
    assert not edges, ("imports from a lower layer into a higher one (move the code to the "
                       "layer it belongs to):\n" + "\n".join(edges))


#: The analysis stage's own layers, bottom first: compiled kernels and the output set; frames
#: (dumps read and checked); records (what the stage hands on); flow metrics; granules; GSD
#: and split outputs; the granule stage; the runners (a study, foreign dumps).
ANALYSIS_LAYERS: tuple[tuple[str, tuple[str, ...]], ...] = (
    ("kernels", ("ligwf.analysis.dumps_numba", "ligwf.analysis.cpm_numba",
                 "ligwf.analysis.pair_table_numba", "ligwf.analysis.granules_numba",
                 "ligwf.analysis.outputs")),
    ("frames", ("ligwf.analysis.frames",)),
    ("records", ("ligwf.analysis.records",)),
    ("flow", ("ligwf.analysis.flow",)),
    ("granules", ("ligwf.analysis.granules",)),
    ("gsd", ("ligwf.analysis.gsd", "ligwf.analysis.parts")),
    ("granule stage", ("ligwf.analysis.granule_stage",)),
    ("runners", ("ligwf.analysis.runner", "ligwf.analysis.foreign")),
)


def _analysis_graph() -> nx.DiGraph:
    return import_graph().subgraph(m for m in MODULES if m.startswith("ligwf.analysis."))


def test_every_analysis_module_has_a_sub_layer():
    homeless = [m for m in _analysis_graph() if layer_of(m, ANALYSIS_LAYERS) is None]
    assert not homeless, f"analysis modules in no sub-layer (add them to ANALYSIS_LAYERS): {homeless}"


def test_analysis_sub_packages_point_one_way():
    # the checker sees the import this rule removed (frames/checks took AXES from granules)
    was = nx.DiGraph([("ligwf.analysis.frames.checks", "ligwf.analysis.granules.bonds")])
    assert up_edges(was, ANALYSIS_LAYERS) == ["ligwf.analysis.frames.checks -> "
                                              "ligwf.analysis.granules.bonds (frames imports granules)"]
    edges = up_edges(_analysis_graph(), ANALYSIS_LAYERS)
    assert not edges, ("inside the analysis stage, imports from a lower sub-layer into a higher "
                       "one (move the shared code down):\n" + "\n".join(edges))


def test_the_layer_check_sees_an_up_edge_inside_a_function(tmp_path):
    """The checker itself: a function-level import of a higher layer is an up-edge, one of
    the same layer or a lower one is not."""
    src = tmp_path / "fake.py"
    src.write_text("from ligwf.study.manifest import DONE\n\n"
                   "def f():\n    from ligwf.pipeline.run import run_study\n")
    g = nx.DiGraph()
    g.add_edges_from(("ligwf.engine.fake", t) for t in _imports("ligwf.engine.fake", src))
    assert up_edges(g) == ["ligwf.engine.fake -> ligwf.pipeline.run (engine imports pipeline)"]
    assert layer_of("ligwf.scene.settings") == 2 and layer_of("ligwf") == 0


def test_no_import_cycle():
    cycles = list(nx.simple_cycles(import_graph()))
    assert not cycles, "import cycles:\n" + "\n".join(" -> ".join(c + [c[0]]) for c in cycles)


def test_no_dynamic_imports():
    pattern = re.compile(r"\bimport_module\s*\(|__import__\s*\(")
    hits = [f"{p.relative_to(ROOT)}:{n}" for p in MODULES.values()
            for n, line in enumerate(p.read_text().splitlines(), 1) if pattern.search(line)]
    assert not hits, f"dynamic imports hide the dependency graph: {hits}"


def _occurrences(pattern: str, allowed: str) -> list[str]:
    rx = re.compile(pattern)
    return [f"{p.relative_to(ROOT)}:{n}: {line.strip()}" for m, p in MODULES.items()
            if not m.startswith(allowed)
            for n, line in enumerate(p.read_text().splitlines(), 1) if rx.search(line)]


def test_study_folder_file_names_only_in_the_study_model():
    hits = _occurrences(r"scene\.json|manifest\.json", "ligwf.study")
    assert not hits, "the study model owns these file names:\n" + "\n".join(hits)


#: the one module that reads and writes each JSON record of a study folder (issue 33)
RECORD_OWNERS = {"STUDY_FILE": "ligwf.study.study_record",
                 "ANALYSIS_RECORD": "ligwf.analysis.records.analysis_record"}
#: a record opened by hand: its path read, or handed to a JSON reader or writer
OPENED = r"{name}\)?\.(read_text|read_bytes|open)\(|json\.(loads?|dumps?)\(.*{name}|atomic_write_json\(.*{name}"


def test_each_record_is_parsed_by_its_type_only():
    hits = [h for name, owner in RECORD_OWNERS.items()
            for h in _occurrences(OPENED.format(name=name), owner)]
    assert not hits, ("read and write these records through StudyRecord / AnalysisRecord:\n"
                      + "\n".join(hits))
    # the pattern sees what the modules did before the record types
    rx = re.compile(OPENED.format(name="ANALYSIS_RECORD"))
    assert rx.search("record = json.loads((where / layout.ANALYSIS_RECORD).read_text())")
    assert re.search(OPENED.format(name="STUDY_FILE"),
                     "atomic_write_json(out_dir / STUDY_FILE, {")
    assert not rx.search('raise MissingAnalysis(f"no record ({layout.ANALYSIS_RECORD})")')


def test_liquid_models_named_only_in_their_modules():
    hits = _occurrences(r"""["'](washino|easo)["']""", "ligwf.liquids")
    assert not hits, "ask ligwf.liquids instead of comparing model names:\n" + "\n".join(hits)


def test_the_checker_sees_function_level_and_relative_imports(tmp_path):
    """The checker itself: an import inside a function and a relative import are edges
    (a cycle cannot hide there)."""
    src = tmp_path / "fake.py"
    src.write_text("from ..engine import site\n\ndef f():\n    from ligwf.cli import main\n")
    assert _imports("ligwf.cli.fake", src) == {"ligwf.engine.site", "ligwf.cli.main"}


def test_the_package_root_reaches_the_api_only_lazily():
    """``ligwf/__init__`` is the base layer, and the import graph lets a package's
    ``__init__`` import its own modules; the root must not use that to import a stage: its
    only import above the base layer is :mod:`ligwf.api`, inside the module
    ``__getattr__`` (and under ``TYPE_CHECKING`` for type checkers), so ``from ligwf
    import open_study`` works and ``import ligwf`` loads no stage."""
    tree = ast.parse(MODULES["ligwf"].read_text())
    lazy = {n for f in tree.body if isinstance(f, ast.FunctionDef) and f.name == "__getattr__"
            for n in ast.walk(f)}
    typing_only = {n for b in tree.body if isinstance(b, ast.If)
                   and "TYPE_CHECKING" in ast.unparse(b.test) for n in ast.walk(b)}
    for node in ast.walk(tree):
        if not isinstance(node, (ast.Import, ast.ImportFrom)):
            continue
        names = ([a.name for a in node.names] if isinstance(node, ast.Import) else
                 [f"{node.module}.{a.name}" for a in node.names])
        for target in filter(None, map(_resolve, names)):
            if node in lazy or node in typing_only:
                assert target == "ligwf.api", ast.unparse(node)
            else:
                assert layer_of(target) == 0, f"ligwf/__init__ imports {target} at import time"
    assert any(isinstance(n, ast.ImportFrom) for n in lazy), "no lazy import of ligwf.api"
