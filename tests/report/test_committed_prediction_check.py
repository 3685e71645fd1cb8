"""docs/results/prediction_check: the README's counts of predictions that hold (measured
half-width within +-30 % of the planner's prediction) are those of the committed table."""

from __future__ import annotations

import re

import pandas as pd

from tests.helpers import ROOT

HERE = ROOT / "docs" / "results" / "prediction_check"


def test_readme_counts_are_the_tables():
    table = pd.read_csv(HERE / "demo.csv")
    text = (HERE / "README.md").read_text()
    for kind, label in (("replicas", "Replicas"), ("extension", "Extension")):
        sub = table[table["kind"] == kind]
        ok = int(sub["within_30_percent"].sum())
        ratios = sub["measured_over_predicted"]
        m = re.search(rf"{label}: .*?holds in (\d+) of (\d+) rows \(measured / predicted "
                      rf"([\d.]+)-([\d.]+)\)", text, re.S)
        assert m, label
        assert (int(m.group(1)), int(m.group(2))) == (ok, len(sub))
        assert float(m.group(3)) == round(ratios.min(), 2)
        assert float(m.group(4)) == round(ratios.max(), 2)
        # the flag is what the ratio says
        assert list(sub["within_30_percent"]) == [abs(r - 1) <= 0.3 for r in ratios]


def test_ladder_counts_are_its_table():
    """The ladder's rows (registered in the README before the check ran): counts over the
    rows with a ratio (a statistic without an interval has none)."""
    table = pd.read_csv(HERE / "ladder.csv")
    text = (HERE / "README.md").read_text()
    for kind, label in (("replicas", "Ladder replicas"), ("extension", "Ladder extension")):
        sub = table[table["kind"] == kind]
        ratios = sub["measured_over_predicted"].dropna()
        ok = int(sub["within_30_percent"].sum())
        m = re.search(rf"{label}: .*?holds in (\d+) of (\d+) rows \(measured / predicted "
                      rf"([\d.]+)-([\d.]+)\)", text, re.S)
        assert m, label
        assert (int(m.group(1)), int(m.group(2))) == (ok, len(ratios))
        assert (float(m.group(3)), float(m.group(4))) == (round(ratios.min(), 2),
                                                          round(ratios.max(), 2))
    ext = table[table["kind"] == "extension"]["measured_over_predicted"].dropna()
    assert "Every miss is\n  on the same side" in text and (ext[(ext - 1).abs() > 0.3] < 1).all()
