"""The committed ladders (docs/results/ladder and its cap_80min/): each README is the text its
tables give (scripts/ladder_results.py --check), and every signed criterion of each
verdict.csv recomputes from the per-run values of its cases.csv with the verdict's
statistics."""

from __future__ import annotations

import pandas as pd
import pytest

from ligwf.inference import equivalence as eq
from ligwf.study.rounds import read_rounds
from scripts.ladder_results import LADDERS, check, main

COMMITTED = [name for name, ladder in LADDERS.items() if (ladder.out / "verdict.csv").exists()]


def test_the_continuation_is_committed_and_check_reads_every_ladder():
    assert "continuation" in COMMITTED
    assert main(["--check"]) == 0


@pytest.mark.parametrize("name", COMMITTED)
def test_readme_is_what_the_tables_say(name):
    assert check(LADDERS[name]) == 0


@pytest.mark.parametrize("name", COMMITTED)
def test_signed_criteria_recompute_from_the_runs(name):
    out = LADDERS[name].out
    verdict = pd.read_csv(out / "verdict.csv")
    cases = pd.read_csv(out / "cases.csv")
    cg1 = cases[cases["cg"] == 1.0]
    rounds = read_rounds(out)              # a sequential study: alpha / looks, Hsu's df
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
