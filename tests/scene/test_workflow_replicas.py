"""Workflow.with_replicas: the typed way a sequential study's rounds add replicas (the
rounds never edit the workflow's YAML). The cases it had keep their ids, scenes and
seeds; more replicas are the cases of the workflow written with them; the written
limits hold."""

from __future__ import annotations

import copy

import pytest
import yaml

from ligwf.errors import ConfigError
from ligwf.scene.workflow import MAX_REPLICAS, expand

from helpers import ROOT

RAW = yaml.safe_load((ROOT / "tests" / "workflows" / "rounds_tiny.yaml").read_text())


def test_more_replicas_are_the_workflow_written_with_them():
    raw = copy.deepcopy(RAW)
    raw["sweep"].update({"rules": ["weber", "bond"], "scene.process.rotation.rpm": [20, 30],
                         "controls": ["cohesionless"]})
    wf = expand(raw)
    more = wf.with_replicas({1.5: 4, 1.0: 1, 7.0: 9})   # fewer than it has, or no such level
    written = copy.deepcopy(raw)
    written["sweep"]["replicas"] = {1: 2, 1.5: 4}
    assert more.cases == expand(written).cases
    assert {c.case_id for c in wf.cases} < {c.case_id for c in more.cases}
    assert more.raw == raw and wf.with_replicas({}).cases == wf.cases


def test_the_written_limits_hold():
    wf = expand(copy.deepcopy(RAW))
    with pytest.raises(ConfigError, match=f"sweep.replicas.1.5 = {MAX_REPLICAS + 1}: allowed"):
        wf.with_replicas({1.5: MAX_REPLICAS + 1})
