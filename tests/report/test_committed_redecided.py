"""docs/results/verdict_rates/redecided_*.csv: the committed ladder and demo verdicts
re-decided with issue 45's rules from their committed tables (scripts/redecide_issue45.py);
the tables recompute, the registered verdict tables are left as they were, and the README's
counts are the tables'."""

from __future__ import annotations

import pandas as pd

from scripts.redecide_issue45 import STUDIES, main, path, redecide
from tests.helpers import ROOT

README = " ".join((ROOT / "docs" / "results" / "verdict_rates" / "README.md").read_text().split())
ASSESSED = ("pass", "fail", "undecided")


def test_the_tables_recompute_from_the_committed_studies():
    assert main(["--check"]) == 0


def test_registered_states_are_the_registered_tables():
    for study in STUDIES:
        table = pd.read_csv(path(study))
        registered = pd.read_csv(study.folder / "verdict.csv")
        assert list(table["old_state"]) == list(registered["state"])


def test_readme_counts_are_the_tables():
    words = {"ladder": "Ladder continuation", "cap_80min": "80-min ladder", "demo": "Demo"}
    for study in STUDIES:
        t = redecide(study)
        a = t[t["old_state"].isin(ASSESSED)]
        changed, depend = int(a["changed"].sum()), int((a["state"].str.startswith("depends")).sum())
        start = README.index(f"- {words[study.name]}")
        segment = README[start:start + 250]
        assert f"{changed} of {len(a)} " in segment and f"{depend} depend" in segment
    ladder = redecide(STUDIES[0]).set_index(["condition", "criterion"])
    for crit, p in (("angle_deg", "0.0054"), ("field_error", "0.0094")):
        row = ladder.loc[("cg3-weber", crit)]
        assert row["state"] == "undecided" and f"{row['p_fail']:.2g}" == p
    for study in STUDIES[:2]:
        t = redecide(study)
        rigid = t[t["criterion"] == "rigid_share"]
        assert (rigid["state"] == "undecided").all() and len(rigid) == 4
    demo = redecide(STUDIES[2]).set_index(["condition", "criterion"])
    bond, weber = demo.loc[("cg2-bond", "angle_deg")], demo.loc[("cg2-weber", "angle_deg")]
    assert bond["state"] == weber["state"] == "undecided"
    assert "Holm" in bond["why"] and f"(fail p {bond['p_fail']:.2g})" in README
    assert "Behrens-Fisher" in weber["why"] and f"(fail p {weber['p_fail']:.2g})" in README
