"""The criterion registry proved by a toy: a criterion that lives in the test folder
(``tests/inference/toy_criterion.py``, one module) reaches the ``accept:`` block, the
verdict and Holm's family, the verdict record (``verdict.csv`` / ``verdict.json``), the
report's verdict table and the data dictionary, with nothing else edited; and the built-in
criteria are exactly the ``accept:`` fields."""

from __future__ import annotations

import pandas as pd
import pytest

from ligwf.errors import ConfigError
from ligwf.inference.budget import BUILT_IN, criteria, signed_columns
from ligwf.inference.equivalence import FAIL, PASS
from ligwf.inference.registry import register, unregister
from ligwf.inference.verdict import FAILS, MEETS
from ligwf.inference.verdict_records import read_verdict, write_verdict
from ligwf.report.dictionary import dictionary_markdown
from ligwf.report.verdict_text import budget_line, verdict_section
from ligwf.scene.accept import AcceptSettings, build_accept_settings
from ligwf.study import layout
from tests.inference.test_verdict import CG1, crit, runs, verdict
from tests.inference.toy_criterion import TOY


@pytest.fixture
def toy():
    register(TOY)
    yield TOY
    unregister(TOY.name)


def test_the_built_in_criteria_are_the_accept_fields_in_order():
    assert [c.name for c in BUILT_IN] == list(AcceptSettings.model_fields)
    assert signed_columns() == ("angle_of_repose", "rigid_frame_share",
                                "flowing_layer_thickness_mean")
    with pytest.raises(ValueError, match="registered already"):
        register(BUILT_IN[0])


def test_the_toy_key_is_a_typo_until_the_toy_registers(toy):
    unregister(toy.name)
    with pytest.raises(ConfigError, match=r"accept\.toy_spread_deg: unknown key"):
        build_accept_settings({"toy_spread_deg": 2.0})
    register(toy)
    accept = build_accept_settings({"toy_spread_deg": 2.0})
    assert accept.tolerance("toy_spread_deg") == 2.0
    assert AcceptSettings().tolerance("toy_spread_deg") == 3.0      # its default
    with pytest.raises(ConfigError, match=r"toy_spread_deg = 100: must be a number in \[0, 90\]"):
        build_accept_settings({"toy_spread_deg": 100})


def test_the_toy_decides_a_level_and_enters_holms_family(toy, tmp_path):
    near = runs(2, "weber", [40.1, 39.9, 40.0])          # every criterion passes
    far = runs(3, "weber", [40.0, 40.2, 45.9])           # one run 5.9 deg from CG1's mean
    v = verdict(CG1, near, far, accept=build_accept_settings({"toy_spread_deg": 2.0}))
    assert [c.name for c in criteria()][-1] == "toy_spread_deg"
    good, bad = crit(v, "cg2-weber")["toy_spread_deg"], crit(v, "cg3-weber")["toy_spread_deg"]
    assert good.state == PASS and good.value == pytest.approx(0.1)
    assert bad.state == FAIL and bad.value == pytest.approx(5.9) and bad.budget == 2.0
    states = {c.name: c.state for g in v.groups for c in g.conditions}
    assert states == {"cg2-weber": MEETS, "cg3-weber": FAILS}
    # the verdict record and the report's verdict table carry it
    write_verdict(v, tmp_path)
    table = pd.read_csv(tmp_path / layout.VERDICT_TABLE)
    row = table[(table["criterion"] == "toy_spread_deg") & (table["cg"] == 3.0)].iloc[0]
    assert row["state"] == FAIL and row["label"] == "toy run spread" and row["unit"] == "deg"
    back = read_verdict(tmp_path)
    assert crit(back, "cg3-weber")["toy_spread_deg"] == bad
    assert back.accept["toy_spread_deg"] == 2.0
    page = verdict_section(back)
    assert "toy run spread (<= 2 deg)" in page
    assert "toy run spread <= 2 deg" in budget_line(back.accept)


def test_without_the_toy_the_verdict_is_the_built_in_one(toy):
    v = verdict(CG1, runs(3, "weber", [40.0, 40.2, 45.9]))
    assert "toy_spread_deg" in crit(v, "cg3-weber")
    unregister(toy.name)
    v = verdict(CG1, runs(3, "weber", [40.0, 40.2, 45.9]))
    assert "toy_spread_deg" not in crit(v, "cg3-weber")
    register(toy)


def test_the_data_dictionary_lists_the_toy(toy):
    text = dictionary_markdown()
    assert "| `toy_spread_deg` | toy run spread | deg | `angle_of_repose` | error | 3 |" in text
    assert "(a toy)" in text
