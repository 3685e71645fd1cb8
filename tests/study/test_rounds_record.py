"""The rounds record's typed actions: each writes and reads its own JSON, the committed
records (the ladder and its 80-minute cap) read as typed actions and are written back
byte for byte, and a record with an action of an unknown kind is refused in one line."""

from __future__ import annotations

import json

import pytest

from ligwf.errors import ConfigError
from ligwf.study.condition import Arm, Condition
from ligwf.study.layout import ROUNDS_FILE
from ligwf.study.rounds import (AddReplicas, ExtendProduction, Look, Rounds, read_action,
                                read_rounds, write_rounds)

from helpers import ROOT

COMMITTED = [ROOT / "docs" / "results" / "ladder", ROOT / "docs" / "results" / "ladder" / "cap_80min"]


@pytest.mark.parametrize("folder", COMMITTED, ids=lambda p: p.name)
def test_a_committed_record_reads_typed_and_is_written_back_byte_for_byte(folder, tmp_path):
    rounds = read_rounds(folder)
    actions = [a for x in rounds.looks for a in x.actions]
    assert actions and all(isinstance(a, (AddReplicas, ExtendProduction)) for a in actions)
    cg1 = [a for a in actions if a.arm == Arm.CG1]
    assert cg1 and all(a.condition == Condition("{}", 1.0, "none") for a in cg1)
    write_rounds(tmp_path, rounds)
    assert (tmp_path / ROUNDS_FILE).read_bytes() == (folder / ROUNDS_FILE).read_bytes()


def test_each_action_writes_the_json_it_reads():
    extend = ExtendProduction(Arm.CG_N, 0.05, ("cg2-weber-r1", "cg2-weber-r0"),
                              {"cg2-weber-r1": 1200, "cg2-weber-r0": 1200})
    add = AddReplicas(Condition('{"process.rotation.rpm": 20}', 2.0, "weber"), (3, 4), 1200)
    assert extend.to_json() == {"kind": "extend", "arm": "CG-n", "seconds": 0.05,
                                "case_ids": ["cg2-weber-r1", "cg2-weber-r0"],
                                "run_steps": {"cg2-weber-r1": 1200, "cg2-weber-r0": 1200}}
    assert add.to_json() == {"kind": "replicas", "arm": "CG-n",
                             "group": '{"process.rotation.rpm": 20}', "cg": 2.0,
                             "rule": "weber", "replicas": [3, 4], "each_run_steps": 1200,
                             "condition": "cg2-weber process.rotation.rpm=20"}
    for action in (extend, add):
        assert read_action(json.loads(json.dumps(action.to_json()))) == action


def test_a_replicas_action_written_without_its_arm_still_reads(tmp_path):
    (tmp_path / ROUNDS_FILE).write_text(json.dumps({"max_looks": 2, "alpha": 0.05, "looks": [
        {"number": 1, "alpha": 0.025, "core_hours": 0.1, "actions": [
            {"kind": "replicas", "group": "", "cg": 1.0, "rule": "none", "replicas": [2],
             "each_run_steps": 100, "condition": "cg1"}]}]}))
    (action,) = read_rounds(tmp_path).looks[0].actions
    assert action == AddReplicas(Condition("", 1.0, "none"), (2,), 100)
    assert action.arm == Arm.CG1


def test_an_action_of_an_unknown_kind_is_refused(tmp_path):
    write_rounds(tmp_path, Rounds(2, looks=(Look(1, 0.025, 0.1),)))
    rec = json.loads((tmp_path / ROUNDS_FILE).read_text())
    rec["looks"][0]["actions"] = [{"kind": "shorten", "arm": "CG1"}]
    (tmp_path / ROUNDS_FILE).write_text(json.dumps(rec))
    with pytest.raises(ConfigError, match="unreadable record of the study's rounds"):
        read_rounds(tmp_path)
