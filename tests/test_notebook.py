"""docs/example.ipynb runs from top to bottom (nbclient, a real IPython kernel) on a tiny
real study (tests/apistudy.py) and reads every table through ``ligwf.open_study``.

The committed notebook is stored without outputs; this test executes a copy in memory.
"""

from __future__ import annotations

import json
import os
import re

import nbformat
import pytest
from nbclient import NotebookClient

from apistudy import api_study
from helpers import ROOT
from ligwf.api import TABLES
from ligwf.study import layout

NOTEBOOK = ROOT / "docs" / "example.ipynb"
#: what the study object read (its table cache and records, ligwf.api.results)
PROBE = ("import json\n"
         "print('READ ' + json.dumps(sorted(study.__dict__.get('_tables', {}))"
         " + [n for n in ('field_record', 'flow_record') if n in study.__dict__]))")


def test_the_committed_notebook_has_no_outputs_and_no_file_names():
    nb = nbformat.read(NOTEBOOK, as_version=4)
    code = "\n".join(c.source for c in nb.cells if c.cell_type == "code")
    assert all(not c.get("outputs") and c.get("execution_count") is None
               for c in nb.cells if c.cell_type == "code")
    names = {t.file for t in TABLES} | {layout.FLOW_PROFILES, layout.ANALYSIS_RECORD,
                                         layout.FIELDS_DATA}
    assert not [n for n in names if n in code]
    assert not re.search(r"read_(csv|parquet|json)|open\(", code)
    assert "ligwf.open_study(" in code


@pytest.mark.engine
@pytest.mark.mpi
def test_the_example_notebook_runs_on_a_real_study(engine, tmp_path_factory, monkeypatch):
    study = api_study(engine, tmp_path_factory)
    nb = nbformat.read(NOTEBOOK, as_version=4)
    nb.cells.append(nbformat.v4.new_code_cell(PROBE))
    monkeypatch.setenv("LIGWF_STUDY", str(study))
    monkeypatch.delenv("MPLBACKEND", raising=False)     # the kernel's inline backend
    NotebookClient(nb, timeout=600, kernel_name="python3",
                   resources={"metadata": {"path": str(NOTEBOOK.parent)}}).execute()
    errors = [o for c in nb.cells for o in c.get("outputs", []) if o.output_type == "error"]
    assert not errors, errors
    probe = "".join(o.get("text", "") for o in nb.cells[-1].outputs)
    read = json.loads(re.search(r"READ (.*)", probe).group(1))
    assert set(read) >= {t.attribute for t in TABLES} | {"field_record"}, read
    pictures = [o for c in nb.cells for o in c.get("outputs", [])
                if "image/png" in o.get("data", {})]
    assert len(pictures) >= 3                       # error vs cost, GSD, speed field
    for shown in ("study.conditions[", "study.verdict["):
        cell = next(c for c in nb.cells if shown in c.source)
        assert any("text/html" in o.get("data", {}) for o in cell.outputs), shown
    verdict = next(c for c in nb.cells if "verdict_result" in c.source)
    assert "->" in "".join(o.get("text", "") for o in verdict.outputs)
    assert os.environ["LIGWF_STUDY"] == str(study)
