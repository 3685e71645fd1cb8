"""A rounds record written before looks stored their ``stop_kind`` (the ladder's look 1)
still says why it stopped: read from the stop's words, so that a stuck or capped study
can be continued by the same command."""

from __future__ import annotations

import json

import pytest

from ligwf.study.layout import ROUNDS_FILE
from ligwf.study.rounds import CAPPED, DECIDED, LOOKS_SPENT, STUCK, read_rounds


@pytest.mark.parametrize("stop, kind", [
    ("no planned way to decide cg2-weber continuum fields: more replicas", STUCK),
    ("the cap of 2.7 core-h cannot decide it: the next round", CAPPED),
    ("decided: cg2-weber meets the budget", DECIDED),
    ("the 3 planned looks are spent; undecided: the next round", LOOKS_SPENT),
    ("", ""),
])
def test_a_legacy_stop_gets_its_kind(tmp_path, stop, kind):
    (tmp_path / ROUNDS_FILE).write_text(json.dumps({"max_looks": 3, "alpha": 0.05, "looks": [
        {"number": 1, "alpha": 0.05 / 3, "core_hours": 3.5, "stop": stop}]}))
    look = read_rounds(tmp_path).looks[0]
    assert look.stop_kind == kind and look.stop == stop


def test_a_stored_kind_wins(tmp_path):
    (tmp_path / ROUNDS_FILE).write_text(json.dumps({"max_looks": 3, "alpha": 0.05, "looks": [
        {"number": 1, "alpha": 0.05 / 3, "core_hours": 3.5, "stop": "no planned way to x",
         "stop_kind": CAPPED}]}))
    assert read_rounds(tmp_path).looks[0].stop_kind == CAPPED
