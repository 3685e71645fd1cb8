"""One freshness rule for the CLI and the API (issue 46 item 5): a table with a missing
or renamed column is a MissingOutput naming the table and the column (it read as a table
with fewer rows or a KeyError later), and ``check()`` names a case whose manifest is
garbage or says killed, as ``ligwf report`` lists it. Real engine output from
``tests/data/cg3_slice``, analysed here."""

from __future__ import annotations

import json
import shutil

import pandas as pd
import pytest

import ligwf
from helpers import ROOT
from ligwf.api import MissingOutput
from ligwf.api.tables import TABLES, column_problem
from ligwf.cli.main import main
from ligwf.report.problems import study_problems
from ligwf.study import layout
from ligwf.study.study import Study

DATA = ROOT / "tests" / "data" / "cg3_slice"
CASE = "cg3-weber-r0"


@pytest.fixture(scope="module")
def analysed(tmp_path_factory):
    study = tmp_path_factory.mktemp("columns") / "study"
    shutil.copytree(DATA, study)
    record = json.loads((study / layout.STUDY_FILE).read_text())
    record["analysis"].update(bootstrap=20, sensitivity_frames=0)
    (study / layout.STUDY_FILE).write_text(json.dumps(record))
    assert main(["analyse", str(study), "--no-vtu"]) == 0
    return study


@pytest.fixture
def study(analysed, tmp_path):
    copy = tmp_path / "study"
    shutil.copytree(analysed, copy)
    return copy


@pytest.mark.parametrize("old,new,said", [
    ("cg", "cg_level", "the flow table has no column 'cg'"),
    ("angle_of_repose", "angle", "column 'angle' is none of the flow table's"),
])
def test_a_renamed_column_is_a_missing_output_naming_table_and_column(study, old, new, said):
    path = study / layout.ANALYSIS_DIR / layout.FLOW_TABLE
    assert len(ligwf.open_study(study).flow) == 1
    pd.read_csv(path).rename(columns={old: new}).to_csv(path, index=False)
    with pytest.raises(MissingOutput) as err:
        ligwf.open_study(study).flow
    assert said in str(err.value) and str(path) in str(err.value)
    assert "run `ligwf analyse" in str(err.value)


def test_column_problem_of_a_report_table():
    spec = {t.attribute: t for t in TABLES}["conditions"]
    good = pd.DataFrame({"group": ["{}"], "group_label": ["all cases"], "cg": [2.0],
                         "rule": ["weber"], "angle_error": [0.5]})
    assert column_problem(good, spec) is None
    assert column_problem(pd.DataFrame(), spec) is None          # an empty table is a table
    assert "no column 'cg'" in column_problem(good.drop(columns="cg"), spec)
    assert "'angle_err'" in column_problem(good.rename(columns={"angle_error": "angle_err"}),
                                            spec)


@pytest.mark.parametrize("manifest,said", [
    ("{garbage", "unreadable manifest"),
    ("killed", "manifest status 'killed'"),
])
def test_check_names_a_garbage_or_killed_manifest_as_the_report_does(study, manifest, said):
    path = study / CASE / layout.MANIFEST_FILE
    if manifest == "killed":
        record = json.loads(path.read_text())
        record["status"] = "killed"
        manifest = json.dumps(record)
    path.write_text(manifest)
    problems = ligwf.open_study(study).check()
    assert problems == study_problems(Study.open(study))       # what `ligwf report` lists
    assert problems.count >= 1 and said in dict(problems.cases)[CASE]
