"""The report says in words when Weber's and Bond's extrapolated CG1 values differ (both
target one CG1: at least one rule does not extrapolate), on the committed tables of the
extrapolation check's two drums: the new drum's rules miss each other, the demo drum's
interval reaches 0."""

from __future__ import annotations

import pandas as pd

from ligwf.report.extrapolation_report import extrapolation_section, rules_disagree
from tests.helpers import ROOT

HERE = ROOT / "docs" / "results" / "extrapolation"


def test_a_disagreement_is_said_and_an_agreement_is_not():
    new = pd.read_csv(HERE / "new_drum_extrapolation.csv")
    row = new[(new["rule"] == "weber - bond") & (new["column"] == "angle_of_repose")].iloc[0]
    assert row["hi"] < 0
    lines = rules_disagree(new)
    assert len([x for x in lines if x]) == 1
    assert lines[1].startswith("- angle_of_repose ({}): Weber's and Bond's extrapolated CG1 "
                               f"values differ by {row['extrapolated']:.3g}")
    (section,) = extrapolation_section(new, 0.0025 / 0.07)
    assert lines[1] in section.markdown
    demo = pd.read_csv(HERE / "demo_drum_extrapolation.csv")
    d = demo[demo["rule"] == "weber - bond"]
    assert ((d["lo"] <= 0) & (d["hi"] >= 0)).all() and rules_disagree(demo) == []
    assert rules_disagree(pd.DataFrame()) == []
