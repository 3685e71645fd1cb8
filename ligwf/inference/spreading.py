"""How much faster placed liquid spreads at CG-n than at CG1, with an interval (pure).

Each case with placed liquid has a spreading time t_q: the revolutions of production until
the initially dry particles hold :data:`~ligwf.analysis.flow.spreading.SPREAD_LEVEL` of
their uniform share of the liquid (:mod:`ligwf.analysis.flow.spreading`). A level's rate
against CG1 is the ratio of geometric means R_n = t_q(CG1) / t_q(CG-n), its interval
Welch's t on the log times of the two arms; the exponent k = log R_n / log n, against the
n^2 that a walk over contacts with n times longer steps predicts. A case that never
reached the level is censored: its level's ratio is then only a bound, and said to be one.
The coverage of Welch's interval on 3 against 3 log times is not measured by a benchmark
here (the report says so).

The null: the CG1 seeds against each other -- the largest ratio of two CG1 seeds' times
(``cg1_spread``), which has to stay well below the effect for the ratios to mean anything
(docs/results/liquid_spreading/criterion.md).
"""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
from scipy import stats

from ligwf.analysis.flow.spreading import DRY_FRACTION, SPREAD_LEVEL, time_to_share

#: one row per case with placed liquid
CASE_COLUMNS = ("group", "rule", "cg", "replica", "case_id", "dry_particles", "particles",
                "t_spread_rev", "censored", "dry_content_share_end", "dry_wet_share_end",
                "revolutions_end")
#: one row per (group, rule, CG level) against the group's CG1
LEVEL_COLUMNS = ("group", "rule", "cg", "runs", "censored_runs", "t_spread_rev_geomean",
                 "cg1_runs", "t_spread_rev_cg1",
                 "rate_ratio", "rate_ratio_low", "rate_ratio_high", "df", "exponent",
                 "exponent_low", "exponent_high", "expected_ratio", "contains_expected",
                 "above_one", "is_bound", "cg1_spread")
LEVEL = 0.95


def spreading_time_meaning() -> str:
    """What a spreading time is, in one sentence (the report's and the dictionary's)."""
    return (f"revolutions of production until the particles dry at the first frame (below "
            f"{DRY_FRACTION:g} of the placed content) hold {SPREAD_LEVEL:g} of their uniform "
            f"share of the liquid")


def case_times(flows) -> pd.DataFrame:
    """One row per case of ``flows`` (CaseFlow records) with a spreading series."""
    rows = []
    for c in flows:
        s = getattr(c, "spreading", None) or {}
        if not s.get("revolutions"):
            continue
        revs, share = s["revolutions"], s["dry_content_share"]
        t, censored = time_to_share(revs, [math.nan if v is None else v for v in share],
                                    SPREAD_LEVEL)
        rows.append({"group": c.group, "rule": c.rule, "cg": float(c.cg),
                     "replica": int(c.replica), "case_id": c.case_id,
                     "dry_particles": int(s["dry_particles"]),
                     "particles": int(s["particles"]), "t_spread_rev": t,
                     "censored": bool(censored),
                     "dry_content_share_end": _last(share),
                     "dry_wet_share_end": _last(s["dry_wet_share"]),
                     "revolutions_end": float(revs[-1])})
    return pd.DataFrame(rows, columns=list(CASE_COLUMNS))


def _last(values) -> float:
    v = [x for x in values if x is not None and math.isfinite(x)]
    return float(v[-1]) if v else math.nan


def welch_log_ratio(reference, level, confidence: float = LEVEL
                    ) -> tuple[float, float, float, float]:
    """(ratio of geometric means reference / level, its interval low and high, Welch df)
    of two arms of positive times; nan interval when an arm has fewer than 2 values."""
    a = np.log(np.asarray(reference, float))
    b = np.log(np.asarray(level, float))
    ratio = float(np.exp(a.mean() - b.mean())) if len(a) and len(b) else math.nan
    if len(a) < 2 or len(b) < 2:
        return ratio, math.nan, math.nan, math.nan
    va, vb = a.var(ddof=1) / len(a), b.var(ddof=1) / len(b)
    se = math.sqrt(va + vb)
    if se == 0.0:
        return ratio, ratio, ratio, math.inf
    df = (va + vb) ** 2 / (va ** 2 / (len(a) - 1) + vb ** 2 / (len(b) - 1))
    half = float(stats.t.ppf(0.5 + confidence / 2.0, df)) * se
    d = a.mean() - b.mean()
    return ratio, float(np.exp(d - half)), float(np.exp(d + half)), float(df)


def replica_spread(times) -> float:
    """The largest ratio of two replicas' times (1 for one run, nan for none)."""
    t = [x for x in times if x > 0 and math.isfinite(x)]
    return float(max(t) / min(t)) if t else math.nan


def level_rates(cases: pd.DataFrame, confidence: float = LEVEL) -> pd.DataFrame:
    """Per (group, rule, CG-n level) the rate ratio against the group's CG1 runs (any
    rule: CG1 is unscaled), its interval, the exponent and the n^2 expectation."""
    rows = []
    if cases.empty:
        return pd.DataFrame(columns=list(LEVEL_COLUMNS))
    for group, g in cases.groupby("group", sort=True):
        ref = g[g.cg == 1.0]
        spread = replica_spread(ref.t_spread_rev)
        for (rule, cg), lv in g[g.cg != 1.0].groupby(["rule", "cg"], sort=True):
            ratio, low, high, df = welch_log_ratio(ref.t_spread_rev, lv.t_spread_rev,
                                                   confidence)
            ln = math.log(cg)
            expected = cg ** 2
            rows.append({"group": group, "rule": rule, "cg": float(cg), "runs": len(lv),
                         "censored_runs": int(lv.censored.sum()),
                         "t_spread_rev_geomean": float(np.exp(np.log(lv.t_spread_rev).mean())),
                         "cg1_runs": len(ref),
                         "t_spread_rev_cg1": float(np.exp(np.log(ref.t_spread_rev).mean()))
                         if len(ref) else math.nan,
                         "rate_ratio": ratio, "rate_ratio_low": low,
                         "rate_ratio_high": high, "df": df,
                         "exponent": math.log(ratio) / ln if ratio > 0 else math.nan,
                         "exponent_low": math.log(low) / ln if low > 0 else math.nan,
                         "exponent_high": math.log(high) / ln if high > 0 else math.nan,
                         "expected_ratio": expected,
                         "contains_expected": bool(low <= expected <= high),
                         "above_one": bool(low > 1.0),
                         # a censored run's time is a lower bound on its own time
                         "is_bound": bool(lv.censored.any() or ref.censored.any()),
                         "cg1_spread": spread})
    return pd.DataFrame(rows, columns=list(LEVEL_COLUMNS))
