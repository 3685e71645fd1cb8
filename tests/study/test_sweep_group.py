"""The sweep group as a value (issue 48 item 2): the text a study stores round-trips, and its
label, control kind and wet group are what the report, the verdict and the granule
controls read."""

from __future__ import annotations

import pytest

from ligwf.study.case import group_label, group_of
from ligwf.study.condition import Condition
from ligwf.study.group import ALL_CASES, SweepGroup


def test_the_stored_text_round_trips_byte_for_byte():
    for varied in ({}, {"process.rotation.rpm": 20.0}, {"b": 1, "a": "x"},
                   {"control": "cohesionless", "liquid.liquid_content": 0.02}):
        text = group_of(varied)
        assert SweepGroup.parse(text).text == text
        assert SweepGroup.parse(text).values == varied


def test_label_control_and_wet_group():
    plain = SweepGroup.parse(group_of({}))
    assert plain.label == ALL_CASES and plain.control is None and plain.wet == plain
    twin = SweepGroup.parse(group_of({"control": "cohesionless",
                                      "process.rotation.rpm": 20.0}))
    assert twin.control == "cohesionless"
    assert twin.label == "cohesionless control, process.rotation.rpm=20"
    assert twin.wet.text == group_of({"process.rotation.rpm": 20.0})
    assert group_label(twin.text) == twin.label


def test_text_that_is_no_group_record_stays_itself():
    for text in ("not json", "[1, 2]", None):
        g = SweepGroup.parse(text)
        assert g.label == str(text) and g.control is None and g.text == str(text)


def test_a_group_text_is_read_once_and_its_value_is_read_only():
    text = group_of({"process.rotation.rpm": 20.0})
    first = SweepGroup.parse(text)
    assert SweepGroup.parse(text) is first
    assert Condition(text, 2.0, "weber").sweep_group is first
    assert Condition(text, 2.0, "weber").reference.sweep_group is first
    with pytest.raises(TypeError):
        first.values["process.rotation.rpm"] = 30.0
    assert SweepGroup.parse(text).values == {"process.rotation.rpm": 20.0}
