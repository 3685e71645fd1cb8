"""Edits are seen (issue 46 item 3): ``study.json`` and every ``scene.json`` carry a seal
of what they were made from; a hand edit is refused (or listed as not used) in one line
naming the field, by ``status``, ``analyse``, ``report``, ``run-case``, ``study
--until-decided`` and ``open_study``, before anything runs or is written."""

from __future__ import annotations

import json

import pytest

import ligwf
from helpers import ROOT
from ligwf.cli.main import main
from ligwf.errors import ConfigError
from ligwf.report.problems import study_problems
from ligwf.study import layout
from ligwf.study.made_from import edit_summary, edited_fields, leaves, seal, sealed
from ligwf.study.study import Study

TINY = ROOT / "tests" / "workflows" / "runner_tiny.yaml"


def test_a_seal_names_changed_added_and_removed_fields():
    content = {"name": "a", "workflow": {"sweep": {"replicas": {1: 2}, "cg_levels": [1, 3]}},
               "cases": [{"cg": 3.0}]}
    stamp = seal(content)
    assert edited_fields(content, stamp) == []
    assert edited_fields(content, None) is None                 # an older record
    assert leaves(content)["workflow.sweep.cg_levels[1]"] == 3
    edited = json.loads(json.dumps(content))                    # JSON keys are text
    assert edited_fields(edited, stamp) == []
    edited["cases"][0]["cg"] = 4.0
    edited["workflow"]["sweep"]["seed"] = 3
    del edited["name"]
    assert edited_fields(edited, stamp) == ["cases[0].cg = 4.0", "workflow.sweep.seed added",
                                            "name removed"]
    assert edited_fields(content, {"sha256": 1}) == ["made_from (not a seal ligwf writes)"]
    assert edit_summary([f"f{k}" for k in range(5)]) == "f0; f1; f2 (and 2 more field(s))"
    record = sealed({"ligwf_version": "1", "x": 1})
    assert record["made_from"] == seal({"x": 1})                # the version is not sealed


@pytest.fixture
def rendered(tmp_path):
    out = tmp_path / "study"
    assert main(["render", str(TINY), "--out", str(out), "--mesh-cache",
                 str(tmp_path / "meshes")]) == 0
    return out


def _edit(study, change) -> None:
    record = json.loads((study / layout.STUDY_FILE).read_text())
    change(record)
    (study / layout.STUDY_FILE).write_text(json.dumps(record))


EDITS = {
    "cg level": (lambda r: r["cases"][1].update(cg=4.0), "cases[1].cg = 4.0"),
    "workflow value": (lambda r: r["workflow"]["scene"]["liquid"].update(surface_tension=0.05),
                       "workflow.scene.liquid.surface_tension = 0.05"),
    "seed": (lambda r: r["workflow"]["scene"].update(seed=20011), "workflow.scene.seed added"),
    "scene hash": (lambda r: r["cases"][0].update(scene_hash="0" * 64), "cases[0].scene_hash"),
    "name": (lambda r: r.update(name="other"), 'name = "other"'),
}


@pytest.mark.parametrize("edit", sorted(EDITS))
def test_an_edited_study_record_is_refused_by_every_command_naming_the_field(
        rendered, tmp_path, capsys, edit):
    change, field = EDITS[edit]
    _edit(rendered, change)
    before = sorted(p.relative_to(rendered) for p in rendered.rglob("*"))
    for argv in (["status", str(rendered)], ["analyse", str(rendered)],
                 ["report", str(rendered), "--no-snapshots"],
                 ["run-case", str(rendered), "--index", "0"],
                 ["study", str(rendered), "--out", str(rendered), "--until-decided"]):
        capsys.readouterr()
        assert main(argv) == 2, argv
        (line,) = capsys.readouterr().err.strip().splitlines()
        assert "edited after ligwf wrote it" in line and field in line, (argv, line)
        assert "Traceback" not in line
    with pytest.raises(ConfigError, match="edited after ligwf wrote it"):
        ligwf.open_study(rendered)
    assert sorted(p.relative_to(rendered) for p in rendered.rglob("*")) == before


def test_analysis_settings_stay_editable(rendered):
    """The record's analysis and accept blocks are the later stages' settings (each stage
    records what it used): not sealed, so setting them by hand still works."""
    _edit(rendered, lambda r: r["analysis"].update(bootstrap=30))
    assert Study.open(rendered).analysis.bootstrap == 30


def test_a_record_without_a_seal_is_read_as_before(rendered):
    _edit(rendered, lambda r: r.pop("made_from"))
    assert len(Study.open(rendered).case_ids) == 2


@pytest.mark.parametrize("case_id", ["../victim", "a/b", ".hidden", "..", "x\ny"])
def test_a_case_id_that_is_no_folder_name_is_refused(rendered, capsys, case_id):
    def change(record):
        record["cases"][0]["case_id"] = case_id
        record.pop("made_from")          # not only the seal: the id itself is refused
    _edit(rendered, change)
    for argv in (["run-case", str(rendered), "--index", "0"], ["status", str(rendered)]):
        capsys.readouterr()
        assert main(argv) == 2
        (line,) = capsys.readouterr().err.strip().splitlines()
        assert "case id" in line and "study.json" in line, line
    assert not (rendered.parent / "victim").exists()


def test_an_edited_case_record_is_named_and_not_used(rendered, capsys):
    case = Study.open(rendered).cases[1]
    record = json.loads((case.path / layout.SCENE_FILE).read_text())
    record["replica"] = 7
    (case.path / layout.SCENE_FILE).write_text(json.dumps(record))
    assert main(["run-case", str(rendered), "--index", "1"]) == 2
    (line,) = capsys.readouterr().err.strip().splitlines()
    assert "scene.json: edited after ligwf wrote it (replica = 7)" in line
    assert "replica = 7" in dict(study_problems(Study.open(rendered)).cases)[case.case_id]
    capsys.readouterr()
    assert main(["status", str(rendered)]) == 0
    assert "replica = 7" in " ".join(capsys.readouterr().err.split())
