"""Every sentence about the verdict's statistics is written from its record (issue 45 item 4):
the interval level, alpha, the degrees-of-freedom rule, the fail test and the family rule of
the report's verdict section and of the "shown within" heading come from
``Verdict.statistics`` (stored in verdict.json), and the hand-written "Welch's 90 %, 5 % each"
is gone from the code and the README."""

from __future__ import annotations

import json
import re

from ligwf.inference import equivalence as eq
from ligwf.inference.verdict import decide
from ligwf.inference.verdict_records import read_verdict, write_verdict
from ligwf.report.verdict_text import verdict_renderables, verdict_section
from ligwf.scene.accept import AcceptSettings
from tests.helpers import ROOT
from tests.inference.test_verdict import CG1, GROUP, PASSING, runs, study


def _verdict(alpha: float, df_rule: str):
    conditions, cases, profiles = study(CG1, runs(2, "weber", [40.1, 39.9, 40.0]),
                                        runs(3, "weber", [40.0, 40.2, 39.9]))
    return decide(conditions, AcceptSettings(), {GROUP: PASSING}, cases, profiles, alpha,
                  df_rule=df_rule)


def test_a_sequential_look_is_called_what_it_is(tmp_path):
    v = _verdict(0.05 / 3, eq.HSU)
    assert v.statistics["alpha"] == 0.05 / 3 and v.statistics["df_rule"] == eq.HSU
    text = verdict_section(v)
    assert "96.7 % interval (Hsu's degrees of freedom min(R1, R2) - 1)" in text
    assert "1.67 % each" in text and "one-sided 98.3 %" in text
    assert "90 %" not in text and "Welch" not in text and "5 % each" not in text
    write_verdict(v, tmp_path)                     # the record carries it
    again = read_verdict(tmp_path)
    assert again.statistics == v.statistics and verdict_section(again) == text


def test_a_single_look_says_welch_for_equal_and_hsu_for_unequal_arms():
    text = verdict_section(_verdict(0.05, eq.WELCH_EQUAL))
    assert "90 % interval (Welch-Satterthwaite degrees of freedom for arms of equal size, " \
           "Hsu's min(R1, R2) - 1 for unequal arms)" in text
    assert "two-sided for the composite null" in text and "every criterion the level was " \
           "tested on" in text


def test_naming_the_cheapest_of_several_levels_discloses_its_error_rate():
    v = _verdict(0.05, eq.WELCH_EQUAL)
    (g,) = v.groups
    assert g.cheapest and len(g.conditions) == 2
    text = verdict_section(v)
    assert "Chosen among 2 levels, each tested at 5 %" in text and "up to 10 % of studies" in text
    terminal = " ".join(str(r) for r in verdict_renderables(v) if hasattr(r, "plain"))
    assert "up to 10 % of studies" in terminal


def test_a_record_without_statistics_states_no_level(tmp_path):
    v = _verdict(0.05, eq.WELCH_EQUAL)
    write_verdict(v, tmp_path)
    record = tmp_path / "verdict.json"       # as written before the field existed
    data = json.loads(record.read_text())
    del data["statistics"]
    record.write_text(json.dumps(data))
    old = read_verdict(tmp_path)
    assert old.statistics == {}
    text = verdict_section(old)
    assert "does not state its alpha" in text and "90 %" not in text


def test_no_hand_written_statistics_are_left():
    hand = re.compile(r"Welch's 90 %|Welch 90 %|5 % each|90 % interval|a 95 % upper bound")
    for path in ("ligwf/report/verdict_text.py", "ligwf/report/dictionary_entries.py",
                 "README.md", "docs/guide/analysis.md", "docs/data_dictionary.md"):
        assert not hand.search((ROOT / path).read_text()), path
