"""The API sees what the CLI sees (issue 32, item 3): no traceback for any argument or
damaged record, report tables held against the report's own digests, and the same list of
what is not used as ``ligwf report`` (case folders the study record leaves out included)."""

from __future__ import annotations

import dataclasses
import json
import shutil

import pytest

import ligwf
from apistudy import api_study
from helpers import ROOT
from ligwf.api import MissingOutput
from ligwf.cli.main import main
from ligwf.errors import ConfigError
from ligwf.report.digests import DIGEST_RECORD, damaged_report_files, record_digests
from ligwf.report.problems import study_problems
from ligwf.study import layout
from ligwf.study.study import Study
from ligwf.study.study_record import StudyRecord

TINY = ROOT / "tests" / "workflows" / "runner_tiny.yaml"


@pytest.fixture(scope="module")
def rendered(tmp_path_factory):
    out = tmp_path_factory.mktemp("damage") / "study"
    assert main(["render", str(TINY), "--out", str(out), "--mesh-cache",
                 str(out.parent / "meshes")]) == 0
    return out


@pytest.mark.parametrize("path", [None, 123, "", 1.5, ["a"]])
def test_open_study_refuses_what_is_no_path_in_one_line(path):
    with pytest.raises(ConfigError, match=r"open_study: path = .*: a study folder"):
        ligwf.open_study(path)


@pytest.mark.parametrize("record", ["[]", "5", '{"granules_absent": 7}', "null"])
def test_a_damaged_analysis_record_is_a_missing_output_not_a_traceback(rendered, tmp_path,
                                                                       record):
    study = tmp_path / "s"
    shutil.copytree(rendered, study)
    (study / layout.ANALYSIS_DIR).mkdir()
    (study / layout.ANALYSIS_DIR / layout.ANALYSIS_RECORD).write_text(record)
    s = ligwf.open_study(study)
    with pytest.raises(MissingOutput, match="run `ligwf analyse"):
        s.gsd
    problems = study_problems(Study.open(study))          # what `ligwf report` lists
    assert problems.count >= 0


def test_a_case_folder_the_record_leaves_out_is_named(rendered, tmp_path):
    study = tmp_path / "s"
    shutil.copytree(rendered, study)
    record = StudyRecord.read(study)          # a record ligwf wrote without that case
    dropped = record.cases[-1].case_id
    dataclasses.replace(record, cases=record.cases[:-1]).write(study)
    cases = dict(study_problems(Study.open(study)).cases)
    assert f"not listed in {layout.STUDY_FILE}" in cases[dropped]


def test_report_digests_catch_an_emptied_or_edited_table(tmp_path):
    (tmp_path / "conditions.csv").write_text("a,b\n1,2\n")
    (tmp_path / "summary.md").write_text("# x\n")
    assert damaged_report_files(tmp_path) == [f"{tmp_path / DIGEST_RECORD}: no readable "
                                              "record of the report's files"]
    record_digests(tmp_path)
    assert damaged_report_files(tmp_path) == []
    (tmp_path / "conditions.csv").write_text("")
    (tmp_path / "summary.md").write_text("# y\n")              # same size, other bytes
    assert [d.split(":")[0] for d in damaged_report_files(tmp_path)] == [
        str(tmp_path / "conditions.csv"), str(tmp_path / "summary.md")]


@pytest.mark.engine
@pytest.mark.mpi
def test_check_refuses_an_emptied_report_table_and_lists_an_edited_case(engine,
                                                                        tmp_path_factory,
                                                                        tmp_path):
    study = tmp_path / "copy"
    shutil.copytree(api_study(engine, tmp_path_factory), study)
    assert ligwf.open_study(study).check().cases == ()
    (study / layout.REPORT_DIR / layout.CONDITIONS_REPORT).write_text("")
    with pytest.raises(MissingOutput, match=r"conditions.csv: changed since the report"):
        ligwf.open_study(study).check()
    main(["report", str(study), "--no-snapshots"])
    assert ligwf.open_study(study).check().cases == ()
    case = next(p for p in sorted(study.iterdir()) if (p / layout.SCENE_FILE).is_file())
    scene = case / layout.SCENE_FILE
    record = json.loads(scene.read_text())
    record["scaled"]["surface_tension"] *= 10                # the record no longer the run's
    scene.write_text(json.dumps(record))
    flagged = dict(ligwf.open_study(study).check().cases)
    assert case.name in flagged and case.name in dict(study_problems(Study.open(study)).cases)
