"""docs/results/regime: the verdict per wet point and definition (controls_verdict.csv and
its page) is what today's criteria make of the committed controls.csv
(scripts/regime_map.py --check)."""

from __future__ import annotations

import pandas as pd

from scripts.regime_map import OUT, SUMMARY, VERDICT, main


def test_the_verdict_recomputes_from_the_committed_measures():
    assert main(["--check"]) == 0


def test_every_wet_point_with_a_twin_is_judged():
    summary, verdict = pd.read_csv(OUT / SUMMARY), pd.read_csv(OUT / VERDICT)
    wet = {p for p in summary["point"] if "twin" not in p}
    assert set(verdict["point"]) == wet
