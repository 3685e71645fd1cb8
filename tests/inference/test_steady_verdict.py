"""Runs long enough to be steady (issue 45 item 3): a run whose automatic steady window
starts at its cap is flagged in the verdict as too short with the production that would fix
it; the planner's extensions keep the truncation at most a quarter of production (the
stated rule, :func:`ligwf.analysis.records.steady_window.least_extension`); "what would
decide" names the CG1 seeds when they bound the degrees of freedom."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from ligwf.analysis.records import steady_window as steady
from ligwf.inference import equivalence as eq
from ligwf.inference import sampling
from ligwf.inference.equivalence import UNDECIDED
from ligwf.inference import planning
from ligwf.report.forest_text import compact_lines
from ligwf.inference.verdict import decide
from ligwf.inference.verdict_records import read_verdict, write_verdict
from ligwf.report.verdict_text import verdict_section
from ligwf.scene.accept import AcceptSettings
from ligwf.study import layout
from tests.inference.test_verdict import CG1, GROUP, PASSING, crit, runs, study, verdict


def test_the_cap_and_the_least_extension_rule():
    assert steady.at_cap(0.5 - 1e-9) and steady.at_cap(0.46) and not steady.at_cap(0.3)
    assert not steady.at_cap(float("nan"))
    # production >= 4 x the truncation: a window at 40 % of 2 s needs 3.2 s, 1.2 s more
    assert steady.least_extension(0.40, 2.0) == pytest.approx(1.2)
    assert steady.least_extension(0.20, 2.0) == 0.0          # already by a quarter
    # at the cap the truncation is only known to lie in [1/2, 1] of production: the middle,
    # 3/4, is taken, so production at least triples (the first rule, 1/2, doubled it)
    assert steady.least_extension(0.47, 2.0) == pytest.approx(4.0)
    assert steady.least_extension(0.47, 2.0, capped_truncation=0.5) == pytest.approx(2.0)
    after = 2.0 + steady.least_extension(0.47, 2.0)
    assert 0.75 * 2.0 / after <= steady.TARGET_SHARE         # the truncation taken is a quarter
    assert 0.5 * 2.0 / after < steady.TARGET_SHARE           # the one seen, less
    # a window measured past the middle of the capped range is sized by what was measured
    assert steady.least_extension(0.47, 2.0, capped_truncation=0.4) == pytest.approx(
        0.47 * 2.0 / steady.TARGET_SHARE - 2.0)


def noise(cases: pd.DataFrame, capped: set[str], production: float = 2.0) -> pd.DataFrame:
    """A noise table as :func:`planning.noise_table` writes it, with the runs in ``capped``
    at their cap (auto steady window) and the rest starting at 10 % of production."""
    rows = []
    for cid in cases["case_id"]:
        fraction = 0.4999 if cid in capped else 0.1
        rows.append({"case_id": cid, planning.WINDOW: (1 - fraction) * production,
                     planning.STEADY_SHARE: 1 - fraction, planning.REPLICA_COST: 3600.0,
                     planning.PRODUCTION_COST: 600.0, planning.AT_CAP: steady.at_cap(fraction),
                     planning.LEAST_EXTENSION: steady.least_extension(fraction, production),
                     planning.within_column("angle_of_repose"): 0.01})
    return pd.DataFrame(rows).set_index("case_id")


def test_a_level_whose_windows_start_at_the_cap_is_flagged_with_what_fixes_it(tmp_path):
    conditions, cases, profiles = study(CG1, runs(2, "weber", [40.1, 39.9, 40.0]),
                                        runs(3, "weber", [40.0, 40.2, 39.9]))
    cg2 = set(cases[cases["cg"] == 2]["case_id"][:2])
    cg1 = set(cases[cases["cg"] == 1]["case_id"][:1])
    v = decide(conditions, AcceptSettings(), {GROUP: PASSING}, cases, profiles,
               noise=noise(cases, cg2 | cg1))
    short = {c.name: c.too_short for c in v.groups[0].conditions}
    assert "2 of 3 CG-n runs and 1 of 3 CG1 runs" in short["cg2-weber"]
    assert "starts at its 50 % cap" in short["cg2-weber"]
    assert "4 s more production on each of those CG-n runs" in short["cg2-weber"]
    assert "production >= 4 x the truncation" in short["cg2-weber"]
    # cg3's own runs start in time, but it shares the capped CG1 run
    assert "1 of 3 CG1 runs" in short["cg3-weber"] and "CG-n" not in short["cg3-weber"]
    md = verdict_section(v)
    assert f"- cg2-weber: {short['cg2-weber']}" in md
    assert any("runs too short" in line for line, _ in compact_lines(v))
    write_verdict(v, tmp_path)
    assert read_verdict(tmp_path).groups[0].conditions[0].too_short == short["cg2-weber"]
    # verdict.csv carries the flag and the sentence on every row of the level
    table = pd.read_csv(tmp_path / layout.VERDICT_TABLE, keep_default_na=False)
    rows = table[table["condition"] == "cg2-weber"]
    assert rows["too_short"].astype(str).eq("True").all()
    assert (rows["too_short_note"] == short["cg2-weber"]).all()
    # every window in time: no flag
    calm = decide(conditions, AcceptSettings(), {GROUP: PASSING}, cases, profiles,
                  noise=noise(cases, set()))
    assert all(c.too_short == "" for c in calm.groups[0].conditions)


def arm(values, within, window, least=0.0):
    n = len(values)
    return sampling.arm(values, [within] * n, [window] * n, steady_share=0.5,
                        replica_core_seconds=36000.0, production_core_seconds=10.0,
                        least_extension=least)


def test_an_extension_keeps_the_truncation_below_the_cap():
    # the scatter is all within-run: a short extension of both arms would decide it
    values = ([1.2, 1.5, 0.9, 1.3], [0.0, 0.3, -0.3, 0.1])
    free = [o for o in sampling.options(arm(values[0], 0.0625, 1.0),
                                        arm(values[1], 0.0625, 1.0), 1.3, 1.0)
            if o.kind == sampling.EXTEND]
    assert free and min(o.amount for o in free) < 1.0
    # runs whose windows start at the cap need 2 s more each: no extension plans less
    capped = [o for o in sampling.options(arm(values[0], 0.0625, 1.0, least=2.0),
                                          arm(values[1], 0.0625, 1.0, least=2.0), 1.3, 1.0)
              if o.kind == sampling.EXTEND]
    assert len(capped) == len(free) and all(o.amount >= 2.0 for o in capped)


def test_what_would_decide_names_the_cg1_seeds_when_they_bound_the_df():
    rng = np.random.default_rng(4)
    cgn = list(40.9 + 0.05 * rng.standard_normal(24))
    conditions, cases, profiles = study(runs(1, "none", [39.0, 40.4, 40.6]),
                                        runs(3, "weber", cgn))
    v = decide(conditions, AcceptSettings(), {GROUP: PASSING}, cases, profiles,
               df_rule=eq.HSU)
    angle = crit(v, "cg3-weber")["angle_deg"]
    assert angle.state == UNDECIDED
    assert "CG1 seeds bound the degrees of freedom (df 2 with 3 CG1 runs against 24 CG-n" \
        in angle.note
    assert "more CG1 seeds decide it" in angle.note
    # equal arms: the CG-n replicas can still narrow it, nothing to name
    even = verdict(CG1, runs(3, "weber", [41.5, 39.5, 43.5]))
    assert "CG1 seeds bound" not in crit(even, "cg3-weber")["angle_deg"].note
