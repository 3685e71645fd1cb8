"""What the verdict's statistics were, as a record, and the sentences written from it.

The verdict record (``verdict.json``'s ``statistics``) says each test's alpha, the interval
level it makes, the degrees-of-freedom rule, the fail test and the family rule; the report's
method paragraph, the "shown within" heading and the cheapest-level disclosure are written
from it (:mod:`ligwf.report.verdict_text`), never by hand, so a sequential study's 96.7 %
intervals with Hsu's degrees of freedom are called that. A record without it (written
before issue 45) gets sentences that name no level.
"""

from __future__ import annotations

import math

from ligwf.inference.equivalence import BINS_RULE_TEXT, DF_RULE_TEXT, FAIL_SIDES, PROFILE_BINS

#: the family rule and the fail test of this version, in words
FAMILY = ("Holm's step-down over the fail tests of every criterion the level was tested on, "
          "each with its own p-value")
FAIL_TEST = {2: "two-sided for the composite null |delta| <= budget",
             1: "one-sided (the interval wholly outside +-budget)"}


def statistics_record(alpha: float, df_rule: str) -> dict:
    """The verdict's statistics as plain values (what ``verdict.json`` stores)."""
    return {"alpha": alpha, "interval_level": 1.0 - 2.0 * alpha, "bound_level": 1.0 - alpha,
            "df_rule": df_rule, "df_text": DF_RULE_TEXT.get(df_rule, df_rule),
            "fail_test": FAIL_TEST[FAIL_SIDES], "family": FAMILY,
            "profile_bins": PROFILE_BINS, "profile_bins_text": BINS_RULE_TEXT[PROFILE_BINS]}


def _pct(x: float) -> str:
    return f"{100.0 * x:.3g} %"


def method_text(stats: dict) -> str:
    """The method sentences of the verdict section, from its statistics record."""
    if not stats or not math.isfinite(float(stats.get("alpha", math.nan))):
        return ("Signed criteria (angle, rigid-block share, flowing layer) are the difference "
                "of run means CG-n - CG1 with a t interval, decided by two one-sided tests "
                "against +-budget; this verdict record does not state its alpha or degrees "
                "of freedom (written before they were recorded).")
    a = float(stats["alpha"])
    return (f"Signed criteria (angle, rigid-block share, flowing layer) are the difference "
            f"of run means CG-n - CG1 with its {_pct(stats['interval_level'])} interval "
            f"({stats['df_text']}): they pass when it lies inside +-budget (two one-sided "
            f"tests, {_pct(a)} each) and fail when the fail test, "
            f"{stats['fail_test']}, rejects at {_pct(a)}; a share whose runs all read 0 in "
            f"an arm is bounded over its runs (rule of three) instead. The velocity profile "
            f"is the distance of the mean profiles less the noise of both arms, with "
            f"one-sided {_pct(stats['bound_level'])} noncentral-F bounds"
            + (f" ({stats['profile_bins_text']})" if stats.get("profile_bins_text") else "")
            + ". A level meets the "
            f"budget when every criterion it was assessed on passes, and fails when one "
            f"fails after {stats['family']}.")


def shown_within_heading(stats: dict) -> str:
    """The heading of the "shown within" list."""
    level = (f"one-sided {_pct(stats['bound_level'])} bounds"
             if stats and math.isfinite(float(stats.get("bound_level", math.nan)))
             else "its interval's bounds")
    return (f"Shown to stay within (the largest error each interval allows: {level}; speedup "
            "beside):")


def cheapest_disclosure(stats: dict, levels: int) -> str:
    """What naming the cheapest of ``levels`` levels that meet costs in error rate: each
    level is tested at alpha, so were every level exactly on the budget some level would be
    named in up to levels x alpha of studies (measured: docs/results/verdict_rates)."""
    alpha = float(stats.get("alpha", math.nan)) if stats else math.nan
    if levels < 2 or not math.isfinite(alpha):
        return ""
    return (f"(Chosen among {levels} levels, each tested at {_pct(alpha)}: were every level "
            f"exactly on the budget, some level would be named in up to "
            f"{_pct(min(1.0, levels * alpha))} of studies.)")
