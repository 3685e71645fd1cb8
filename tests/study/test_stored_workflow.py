"""The workflow a study folder stores comes back as it was written: JSON keeps object keys
as text, so the sweep's per-CG-level maps (``replicas: {1: 2, 2: 3}``, ``per_cg``) must be
numbers again before the workflow's strict validation sees them (``ligwf study DIR
--until-decided`` on an existing study re-prepares from it)."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
import yaml

from ligwf.errors import ConfigError
from ligwf.scene.workflow import expand
from ligwf.study.layout import STUDY_FILE
from ligwf.study.study import Study


def _store(tmp_path, workflow: dict):
    (tmp_path / STUDY_FILE).write_text(json.dumps({"workflow": workflow, "cases": []}))
    return Study.workflow_of(tmp_path)


def test_cg_keyed_maps_come_back_as_numbers(tmp_path):
    raw = _store(tmp_path, {"sweep": {"cg_levels": [1, 2, 2.5], "replicas": {1: 2, 2: 3, 2.5: 1},
                                      "per_cg": {2: {"process.run_time": 4.0}}}})
    assert raw["sweep"]["replicas"] == {1: 2, 2: 3, 2.5: 1}
    assert list(raw["sweep"]["per_cg"]) == [2]
    assert all(isinstance(k, (int, float)) for k in raw["sweep"]["replicas"])


def test_the_ladder_workflow_survives_its_study_record(tmp_path):
    wf = yaml.safe_load((Path(__file__).parents[2] / "workflows" / "ladder.yaml").read_text())
    direct = expand(wf)
    stored = expand(_store(tmp_path, wf))
    assert [c.case_id for c in stored.cases] == [c.case_id for c in direct.cases]


def test_a_text_level_is_still_refused_by_the_validation(tmp_path):
    wf = yaml.safe_load((Path(__file__).parents[2] / "workflows" / "ladder.yaml").read_text())
    wf["sweep"]["replicas"] = {1: 2, "two": 3}
    raw = _store(tmp_path, wf)
    assert raw["sweep"]["replicas"] == {1: 2, "two": 3}
    with pytest.raises(ConfigError, match="sweep.replicas"):
        expand(raw)
