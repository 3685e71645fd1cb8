"""The committed ladder (docs/results/ladder): its README is the text its tables give
(scripts/ladder_results.py --check), and every signed criterion of its verdict.csv
recomputes from the per-run values of its cases.csv with the verdict's statistics."""

from __future__ import annotations

import pandas as pd
import pytest

from ligwf.analysis.records import equivalence as eq
from ligwf.study.rounds import read_rounds
from scripts.ladder_results import OUT, main

pytestmark = pytest.mark.skipif(not (OUT / "verdict.csv").exists(),
                                reason="the ladder's tables are not committed yet")


def test_readme_is_what_the_tables_say():
    assert main(["--check"]) == 0


def test_signed_criteria_recompute_from_the_runs():
    verdict = pd.read_csv(OUT / "verdict.csv")
    cases = pd.read_csv(OUT / "cases.csv")
    cg1 = cases[cases["cg"] == 1.0]
    rounds = read_rounds(OUT)              # a sequential study: alpha / looks, Hsu's df
    alpha, df_rule = ((rounds.alpha_per_look, eq.HSU) if rounds.looks else (eq.ALPHA, eq.WELCH))
    columns = {"angle_deg": "angle_of_repose", "rigid_share": "rigid_frame_share",
               "flowing_layer": "flowing_layer_thickness_mean"}
    for _, r in verdict[verdict["criterion"].isin(list(columns))].iterrows():
        col = columns[r["criterion"]]
        arm = cases[(cases["cg"] == r["cg"]) & (cases["rule"] == r["rule"])]
        e = eq.difference_estimate(arm[col], cg1[col], alpha, df_rule)
        if r["criterion"] == "flowing_layer":     # relative to the CG1 mean
            e = eq.scaled(e, 1.0 / float(cg1[col].mean()))
        assert e.value == pytest.approx(r["value"], abs=1e-9)
        if e.has_interval:
            assert (e.lo, e.hi) == (pytest.approx(r["lo"], abs=1e-9),
                                    pytest.approx(r["hi"], abs=1e-9))
        state = eq.equivalence(e, r["budget"], alpha).state
        assert r["state"] == state or (state == eq.FAIL and "Holm" in str(r["note"]))
