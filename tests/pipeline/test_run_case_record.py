"""ligwf run-case (a scheduler's array task) runs a case only while its scene record is the
one rendering wrote (issue 32, item 4): the content hash covers the scaled values, input
and mesh, so an original scene block edited after rendering (surface tension x 10) is
caught by scaling it again, refused in one line before anything is written, and named by
what ``ligwf report`` / ``StudyResults.check()`` list as not used."""

from __future__ import annotations

import json

from helpers import ROOT
from ligwf.cli.main import main
from ligwf.report.problems import study_problems
from ligwf.study import layout
from ligwf.study.study import Study

TINY = ROOT / "tests" / "workflows" / "runner_tiny.yaml"


def test_run_case_refuses_a_case_whose_original_scene_no_longer_gives_its_scaled_one(
        tmp_path, capsys):
    study = tmp_path / "s"
    assert main(["render", str(TINY), "--out", str(study), "--mesh-cache",
                 str(tmp_path / "meshes")]) == 0
    case = Study.open(study).cases[0]
    record = json.loads((case.path / layout.SCENE_FILE).read_text())
    record["scene"]["liquid"]["surface_tension"] *= 10
    (case.path / layout.SCENE_FILE).write_text(json.dumps(record))
    capsys.readouterr()
    assert main(["run-case", str(study), "--index", str(case.index)]) == 2
    (line,) = capsys.readouterr().err.strip().splitlines()
    # the record's seal names the edited field itself (issue 46 item 3)
    assert "not run" in line and "edited after ligwf wrote it" in line, line
    assert "scene.liquid.surface_tension = 0.24" in line
    assert not (case.path / layout.MANIFEST_FILE).exists()
    assert "scene.liquid.surface_tension = 0.24" in dict(
        study_problems(Study.open(study)).cases)[case.case_id]


def test_an_unsealed_record_is_still_checked_by_scaling_it_again(tmp_path, capsys):
    """A scene record written before records were sealed (no ``made_from``): the edit is
    still caught by scaling its original block again, as before."""
    study = tmp_path / "s"
    assert main(["render", str(TINY), "--out", str(study), "--mesh-cache",
                 str(tmp_path / "meshes")]) == 0
    case = Study.open(study).cases[0]
    record = json.loads((case.path / layout.SCENE_FILE).read_text())
    del record["made_from"]
    record["scene"]["liquid"]["surface_tension"] *= 10
    (case.path / layout.SCENE_FILE).write_text(json.dumps(record))
    capsys.readouterr()
    assert main(["run-case", str(study), "--index", str(case.index)]) == 2
    (line,) = capsys.readouterr().err.strip().splitlines()
    assert "original scene block no longer gives" in line and "scaled.surface_tension" in line
