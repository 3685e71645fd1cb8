"""The analysis -> report contract, checked on the code: the report reads the analysis
through ligwf.analysis.records only, and the two stages name no output file outside
ligwf/study/layout.py."""

from __future__ import annotations

import ast
import re
from pathlib import Path

import pytest

from helpers import ROOT

PKG = ROOT / "ligwf"
#: the stress suite's report reads the engine's dumps itself (the suite has no analysis)
DUMP_READER = {"ligwf/report/stability.py": {"ligwf.analysis.frames.dumps"}}


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


#: a quoted file name with the extension of an output (csv, json, parquet, pvd, vtu, png, md,
#: html); allowed: temporary files and the engine's dump names a foreign run is read by
FILE_NAME = re.compile(r"""["'][\w.*{}<>-]*\.(csv|json|parquet|pvd|vtu|png|md|html)["']""")
NOT_OUTPUTS = {'"frame.vtu"', '".tmp.vtu"', '"particles_*.vtu"', '"contacts_*.vtu"'}


@pytest.mark.parametrize("path", sorted([*(PKG / "analysis").rglob("*.py"),
                                         *(PKG / "report").glob("*.py")]),
                         ids=lambda p: str(p.relative_to(PKG)))
def test_output_file_names_only_in_the_layout(path):
    code = [n for n in ast.walk(ast.parse(path.read_text()))
            if isinstance(n, ast.Constant) and isinstance(n.value, str)
            and not n.value.count("\n")]           # docstrings are prose, not names
    found = {m.group(0) for n in code for m in [FILE_NAME.fullmatch(repr(n.value).replace("'", '"'))] if m}
    assert found <= NOT_OUTPUTS, f"{path}: {sorted(found - NOT_OUTPUTS)} (declare it in study/layout.py)"
