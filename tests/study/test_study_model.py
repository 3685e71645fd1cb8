"""The study model: file names, case folders parsed once, study listing, analysis settings
from the workflow to the study record and back (no engine needed)."""

from __future__ import annotations

import json

import pytest

from ligwf.cli.main import main
from ligwf.errors import ConfigError
from ligwf.scene.workflow import load_workflow
from ligwf.study import layout
from ligwf.study.case import CaseFolder
from ligwf.study.manifest import Manifest
from ligwf.scene.settings import AnalysisSettings
from ligwf.study.study import Study, studies_below

from helpers import DRUM


@pytest.fixture
def rendered(tmp_path, monkeypatch):
    monkeypatch.setenv("LIGWF_MESH_CACHE", str(tmp_path / "cache"))
    out = tmp_path / "study"
    assert main(["render", str(DRUM), "--out", str(out), "--set", "sweep.cg_levels=[1,2]",
                 "--set", "analysis.max_velocity_angle=10",
                 "--set", "analysis.steady_after=0.5"]) == 0
    return out


def test_analysis_block_is_validated_with_field_and_range(capsys, tmp_path):
    wf = load_workflow(DRUM, ["analysis.bootstrap=50"])
    assert wf.analysis == AnalysisSettings(granules="communities", bootstrap=50)
    assert load_workflow(DRUM).analysis == AnalysisSettings(granules="communities")
    for override, text in [("analysis.steady_after=1.5", "allowed range [0, 1)"),
                           ("analysis.max_velocity_angle=200", "allowed range [0, 180]"),
                           ("analysis.bins=3", "analysis.bins: unknown key")]:
        with pytest.raises(ConfigError, match=r"analysis\.") as exc:
            load_workflow(DRUM, [override])
        assert text in str(exc.value)
    out = tmp_path / "refused"
    assert main(["render", str(DRUM), "--out", str(out), "--set",
                 "analysis.min_particles=0"]) == 2
    assert "analysis.min_particles = 0" in capsys.readouterr().err and not out.exists()


def test_study_stores_and_reads_the_analysis_settings(rendered):
    study = Study.open(rendered)
    assert study.analysis == AnalysisSettings(granules="communities", max_velocity_angle=10,
                                              steady_after=0.5)   # drum.yaml's block + --set
    record = json.loads((rendered / layout.STUDY_FILE).read_text())
    assert record["analysis"]["max_velocity_angle"] == 10
    # a study written before the analysis block existed: the defaults
    del record["analysis"]
    (rendered / layout.STUDY_FILE).write_text(json.dumps(record))
    assert Study.open(rendered).analysis == AnalysisSettings()


def test_cases_in_index_order_parsed_once(rendered):
    study = Study.open(rendered)
    assert list(study.case_ids) == ["cg1-none-r0", "cg2-weber-r0", "cg2-bond-r0"]
    cases = study.cases
    assert [c.index for c in cases] == [0, 1, 2] and study.cases is cases
    c = study.case(1)
    assert (c.case_id, c.cg, c.rule, c.replica, c.group) == ("cg2-weber-r0", 2.0, "weber", 0, "{}")
    s = c.scaled
    assert c.production_start_step == s.insertion_steps + s.numerics.settle_steps
    assert c.steady_start_step(0.5) == c.production_start_step + 0.5 * s.numerics.run_steps
    assert c.drum_angle(c.production_start_step) == 0.0
    assert c.drum_angle(c.production_start_step + 10) == pytest.approx(s.drum.omega * 10 * s.numerics.dt)
    with pytest.raises(ConfigError, match="case index 3"):
        study.case(3)


def test_usability_from_the_manifest(rendered):
    study = Study.open(rendered)
    c = study.case(0)
    assert "no manifest" in c.why_not_usable()
    m = Manifest(case_id=c.case_id, index=0, scene_hash=c.scene_hash, ligwf_version="x",
                 liggghts_version="y", status="done")
    c.write_manifest(m)
    assert c.usable() and c.manifest().status == "done"
    m.status = "failed"
    m.reason = "boom"
    c.write_manifest(m)
    assert c.why_not_usable() == "manifest status 'failed': boom"
    m.status, m.scene_hash = "done", "stale"
    c.write_manifest(m)
    assert "scene hash differs" in c.why_not_usable()
    (study.case_dirs[2] / layout.SCENE_FILE).unlink()
    usable, skipped = study.usable_cases(require_manifest=False)
    assert [u.case_id for u in usable] == ["cg1-none-r0", "cg2-weber-r0"]
    assert skipped[0]["case_id"] == "cg2-bond-r0" and "not a readable case" in skipped[0]["reason"]


def test_single_case_folder_and_suites(rendered, tmp_path):
    one = Study.open(rendered / "cg1-none-r0")
    assert one.single_case and one.analysis == AnalysisSettings()
    assert [c.case_id for c in one.cases] == ["cg1-none-r0"]
    assert [s.path for s in studies_below(rendered)] == [rendered]
    assert [s.path for s in studies_below(tmp_path)] == [rendered]
    with pytest.raises(ConfigError, match="not a ligwf study folder"):
        Study.open(tmp_path)
    with pytest.raises(ConfigError, match="not a readable case folder"):
        CaseFolder.open(tmp_path)
