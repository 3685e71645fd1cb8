"""One Axis value from the workflow's letter to the array columns."""

from __future__ import annotations

import json

from ligwf.scene.axis import Axis
from ligwf.scene.workflow import load_workflow

from helpers import DRUM


def test_the_letter_is_the_value_and_the_columns_follow_from_it():
    assert [a.index for a in Axis] == [0, 1, 2]
    assert {a: a.frame for a in Axis} == {Axis.X: (0, 1, 2), Axis.Y: (1, 0, 2),
                                          Axis.Z: (2, 0, 1)}
    assert all(a.frame[0] == a.index for a in Axis)
    assert str(Axis.Y) == f"{Axis.Y}" == "y" and json.dumps(Axis.Z) == '"z"'


def test_a_workflow_letter_becomes_an_axis_and_records_keep_the_letter():
    s = load_workflow(DRUM, ["scene.drum.axis=z", "scene.drum.periodic=false"]).cases[0].scaled()
    assert s.drum.axis is Axis.Z and s.drum.periodic_axis is None
    assert s.to_dict()["axis"] == "z" and type(s.to_dict()["axis"]) is str
