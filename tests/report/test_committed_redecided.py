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
        start = README.index(f"- {words[study.name]}: ")
        assert README[start:].startswith(f"- {words[study.name]}: {changed} of {len(a)} ")
        assert f"{depend} " in README[start:start + 160]
    ladder = redecide(STUDIES[0]).set_index(["condition", "criterion"])
    for crit, p in (("angle_deg", "0.0054"), ("field_error", "0.0094")):
        row = ladder.loc[("cg3-weber", crit)]
        assert row["state"] == "undecided" and f"{row['p_fail']:.2g}" == p
    for study in STUDIES[:2]:
        t = redecide(study)
        rigid = t[t["criterion"] == "rigid_share"]
        assert (rigid["state"] == "undecided").all() and len(rigid) == 4
    demo = redecide(STUDIES[2])
    angles = demo[demo["criterion"] == "angle_deg"]
    assert (angles["state"] == "undecided").all() and angles["why"].str.contains(
        "degrees of freedom").all()
