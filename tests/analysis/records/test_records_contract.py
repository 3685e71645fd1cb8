"""The analysis -> report contract, checked on the code: the report reads the analysis
through ligwf.analysis.records only; and no module of ligwf names a file or folder it
writes or reads (f-strings included) outside ligwf/study/layout.py."""

from __future__ import annotations

import ast
import re
from pathlib import Path

import pytest

from helpers import ROOT

PKG = ROOT / "ligwf"
#: the stress suite's report reads the engine's dumps itself (the suite has no analysis);
#: the data dictionary reads the flow metrics' declarations (their units and meanings), not
#: an output of the analysis
DUMP_READER = {"ligwf/report/stability.py": {"ligwf.analysis.frames.dumps"},
               "ligwf/report/dictionary.py": {"ligwf.analysis.flow.registry"}}


def imports(path: Path) -> set[str]:
    """Every module ``path`` imports, function-level imports included."""
    out = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.ImportFrom) and node.module:
            out.add(node.module)
        elif isinstance(node, ast.Import):
            out.update(a.name for a in node.names)
    return out


@pytest.mark.parametrize("path", sorted((PKG / "report").glob("*.py")), ids=lambda p: p.name)
def test_report_reads_the_analysis_through_its_records_only(path):
    rel = str(path.relative_to(ROOT))
    analysis = {m for m in imports(path) if m == "ligwf.analysis" or m.startswith("ligwf.analysis.")}
    allowed = DUMP_READER.get(rel, set())
    assert {m for m in analysis if not m.startswith("ligwf.analysis.records")} <= allowed


#: a file name with the extension of a file ligwf writes or reads (a study's records,
#: tables, figures, dumps, logs, scripts, locks, meshes, restarts, archives)
FILE_NAME = re.compile(r"[\w.*{}<>-]*\.(csv|json|parquet|pvd|vtu|vti|png|md|html|log|sh|lock|"
                       r"stl|npz|pkl|liggghts)")
#: names that are not ligwf's files: temporary files (in a temporary folder, or beside the
#: file they become), the dump the engine's VTK warm-up creates and never writes
#: and the repository's documents the generated references link to
NOT_OUTPUTS = {"frame.vtu", ".tmp.vtu", "warm_*.vtu", "README.md", "workflow.schema.json"}
#: path parts joined outside the layout that are not a study's, suite's or calibration's:
#: the installed templates, the site file and its config folder, caches of Python and numba
NOT_STUDY_PARTS = {"templates", "site.yaml", "ligwf", ".config", "__pycache__", "frame.vtu",
                   "ligwf-numba-cache-{}"}
LAYOUT = PKG / "study" / "layout.py"


def _text(node: ast.AST) -> str | None:
    """A string constant, or an f-string with ``{}`` for each value (its constant parts)."""
    if isinstance(node, ast.Constant) and isinstance(node.value, str):
        return node.value
    if isinstance(node, ast.JoinedStr):
        return "".join(v.value if isinstance(v, ast.Constant) else "{}" for v in node.values)
    return None


def file_names(source: str) -> set[str]:
    """File names in the code of ``source``: every word of a one-line string constant or
    f-string that names a file (the last part of a path; a bare suffix such as ``.csv``
    is not a name; paths into docs/ and web addresses are references, not files)."""
    tree = ast.parse(source)
    in_fstring = {id(v) for n in ast.walk(tree) if isinstance(n, ast.JoinedStr) for v in n.values}
    prose = {id(n.value) for n in ast.walk(tree) if isinstance(n, ast.Expr)}   # docstrings
    found = set()
    for node in ast.walk(tree):
        text = _text(node)
        if text is None or id(node) in in_fstring or id(node) in prose:
            continue
        for word in re.split(r"[\s'\"()\[\],;=]+", text):
            if word.startswith("docs/") or "://" in word:
                continue
            name = word.strip("`").rstrip(".:").rsplit("/", 1)[-1]
            if FILE_NAME.fullmatch(name) and not re.fullmatch(r"\.\w+", name):
                found.add(name)
    return found


def joined_parts(source: str) -> set[str]:
    """Every string (or f-string) joined onto a path with ``/``: a file or folder name."""
    found = set()
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.BinOp) and isinstance(node.op, ast.Div):
            found.update(t for side in (node.left, node.right) if (t := _text(side)) is not None)
    return found


def test_the_name_checks_see_f_strings_and_joined_folders():
    src = ('def f(case, n):\n'
           '    """A docstring naming study.json\n    over lines."""\n'
           '    a = case / "post"\n'
           '    b = case / f"run.{n}.log"\n'
           '    log(f"see {case} (summary.md)", "x.csv", "table is .parquet", "docs/a.md",\n'
           '        "https://x.org/s.json", "one line: y.json.")\n'
           '    "a string statement naming z.csv"\n')
    assert file_names(src) == {"run.{}.log", "summary.md", "x.csv", "y.json"}
    assert joined_parts(src) == {"post", "run.{}.log"}


@pytest.mark.parametrize("path", sorted(p for p in PKG.rglob("*.py") if p != LAYOUT),
                         ids=lambda p: str(p.relative_to(PKG)))
def test_output_file_names_only_in_the_layout(path):
    """Every file and folder name ligwf writes or reads is declared in ligwf/study/layout.py:
    no other module spells a file name (f-strings included) or joins a literal name onto
    a path."""
    source = path.read_text()
    names = file_names(source) - NOT_OUTPUTS
    assert not names, f"{path}: {sorted(names)} (declare it in study/layout.py)"
    parts = joined_parts(source) - NOT_STUDY_PARTS
    assert not parts, f"{path}: joins {sorted(parts)} onto a path (declare it in study/layout.py)"
