#!/usr/bin/env python3
"""The committed verdicts re-decided with issue 45's rules, from their committed tables only
(issue 45 item 6): docs/results/verdict_rates/redecided_<study>.csv, one row per (condition,
criterion) with the registered state, the state under the new rules and why it changed. The
registered tables are not touched.

What can be recomputed from committed tables: the signed criteria (cases.csv: angle,
flowing layer, rigid share, with the all-zero bound), the field criterion's fail p
(conditions.csv noise pieces; its bounds are the registered ones) and Holm over the level.
The per-run velocity profiles are not committed: the profile keeps its registered state, and
its fail p is only known to lie below alpha (a registered fail) or at or above it (else).
Holm's outcome is monotone in each p, so it is evaluated at both ends of that range; where
the two ends disagree the row says so ("depends on an uncommitted p"). The same holds
for the field criterion of a table without its noise pieces (the demo's).

    .venv/bin/python scripts/redecide_issue45.py            # writes the tables
    .venv/bin/python scripts/redecide_issue45.py --check    # the committed tables recompute
"""

from __future__ import annotations

import math
import sys
from dataclasses import dataclass
from pathlib import Path

import pandas as pd

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from ligwf.api.results_folder import ResultsFolder, csv_text, results_command  # noqa: E402
from ligwf.inference import equivalence as eq  # noqa: E402
from ligwf.inference.budget import criteria  # noqa: E402
from ligwf.inference.field_errors import FIELD_NOISE_COLUMNS, LayerNoise  # noqa: E402
from ligwf.inference.registry import DIFFERENCES, RELATIVE  # noqa: E402
from ligwf.inference.shares import share_test  # noqa: E402
from ligwf.study import layout  # noqa: E402
from ligwf.study.rounds import read_rounds  # noqa: E402

OUT = ROOT / "docs" / "results" / "verdict_rates"
#: the signed criteria (a difference of run means, recomputable from cases.csv), by name
SIGNED = {c.name: c for c in criteria() if c.estimate in DIFFERENCES}


@dataclass(frozen=True)
class Study:
    name: str
    folder: Path


STUDIES = (Study("ladder", ROOT / "docs" / "results" / "ladder"),
           Study("cap_80min", ROOT / "docs" / "results" / "ladder" / "cap_80min"),
           Study("demo", ROOT / "docs" / "results" / "demo"))


def levels(folder: Path) -> tuple[float, str]:
    """(alpha, df rule) under the new rules: a sequential study's looks keep alpha / looks
    and Hsu's df; a single look Welch's df for equal arms, Behrens-Fisher for unequal ones."""
    rounds = read_rounds(folder)
    return (rounds.alpha_per_look, eq.HSU) if rounds.looks else (eq.ALPHA, eq.WELCH_BF)


def _signed(x, y, name: str, budget: float, alpha: float, df_rule: str
            ) -> tuple[str, float, float, float, str]:
    """(state, lo, hi, fail p, why) of a signed criterion under the new rules."""
    if SIGNED[name].share:
        zero = share_test(x, y, budget, alpha)
        if zero is not None:
            e, t = zero
            return t.state, e.lo, e.hi, t.p_fail, "an arm reads 0 in every run: bounded over runs"
    def test(rule: str, sides: int) -> tuple[eq.Estimate, eq.Test]:
        e = eq.difference_estimate(x, y, alpha, rule)
        if SIGNED[name].estimate == RELATIVE:
            e = eq.scaled(e, 1.0 / float(y.mean()))
        return e, eq.equivalence(e, budget, alpha, fail_sides=sides)

    old_rule = eq.HSU if df_rule == eq.HSU else eq.WELCH     # the registered tables' rules
    e, t = test(df_rule, 2)
    before = test(old_rule, 1)[1].state
    why = [what for what, (rule, sides) in (
        (f"degrees of freedom: {eq.DF_RULE_TEXT[df_rule]}", (df_rule, 1)),
        ("two-sided fail test", (old_rule, 2))) if test(rule, sides)[1].state != before]
    if t.state != before and not why:
        why = [f"the two together: {eq.DF_RULE_TEXT[df_rule]} and a two-sided fail test"]
    return t.state, e.lo, e.hi, t.p_fail, "; ".join(why)


def redecide(study: Study) -> pd.DataFrame:
    verdict = pd.read_csv(study.folder / layout.VERDICT_TABLE)
    cases = pd.read_csv(study.folder / layout.CASES_REPORT)
    conditions = pd.read_csv(study.folder / layout.CONDITIONS_REPORT)
    alpha, df_rule = levels(study.folder)
    cg1 = cases[cases["cg"] == 1.0]
    rows = []
    for (cg, rule), sub in verdict.groupby(["cg", "rule"], sort=True):
        arm = cases[(cases["cg"] == cg) & (cases["rule"] == rule)]
        crit = []
        for _, r in sub.iterrows():
            old, name = str(r["state"]), str(r["criterion"])
            row = dict(condition=r["condition"], criterion=name, old_state=old,
                       old_lo=r["lo"], old_hi=r["hi"], budget=r["budget"])
            if name in SIGNED:
                col = SIGNED[name].metric
                state, lo, hi, p, why = _signed(arm[col].to_numpy(float), cg1[col].to_numpy(float),
                                                name, float(r["budget"]), alpha, df_rule)
                crit.append(dict(row, own_state=state, lo=lo, hi=hi, p_fail=p, why=why,
                                 p_range=(p, p)))
            elif (name == "field_error" and old in (eq.PASS, eq.FAIL, eq.UNDECIDED)
                  and all(k in conditions for k in FIELD_NOISE_COLUMNS)):
                c = conditions[(conditions["cg"] == cg) & (conditions["rule"] == rule)].iloc[0]
                v = [c[k] for k in FIELD_NOISE_COLUMNS]
                p = LayerNoise(*v[:3], int(v[3]), int(v[4])).fail_p(float(r["budget"]))
                own = old
                if old == eq.UNDECIDED and "Holm" in str(r["note"]):
                    own = eq.FAIL
                crit.append(dict(row, own_state=own, lo=r["lo"], hi=r["hi"], p_fail=p,
                                 why="", p_range=(p, p)))
            elif name in ("profile_error", "field_error") and old in (eq.PASS, eq.FAIL,
                                                                      eq.UNDECIDED):
                # per-run profiles (and, in older tables, the field's noise pieces) are
                # not committed: the p lies below alpha for a registered fail, else above
                own = eq.FAIL if (old == eq.FAIL or (old == eq.UNDECIDED and "Holm" in
                                                     str(r["note"]))) else old
                rng = (1e-12, alpha * (1 - 1e-9)) if own == eq.FAIL else (alpha, 1.0)
                crit.append(dict(row, own_state=own, lo=r["lo"], hi=r["hi"], p_fail=math.nan,
                                 why="", p_range=rng))
            else:
                crit.append(dict(row, own_state=old, lo=r["lo"], hi=r["hi"], p_fail=math.nan,
                                 why="", p_range=(math.nan, math.nan)))
        ends = []
        for end in (0, 1):
            p = [c["p_range"][end] for c in crit]
            kept = eq.holm_rejects(p, alpha)
            ends.append([eq.UNDECIDED if c["own_state"] == eq.FAIL and not k else c["own_state"]
                         for c, k in zip(crit, kept)])
        family = sum(math.isfinite(c["p_range"][0]) for c in crit)
        for c, a, b in zip(crit, *ends):
            state = a if a == b else "depends on an uncommitted p"
            why = [c["why"]] if c["why"] else []
            if c["own_state"] == eq.FAIL and a != b:
                why.append(f"whether its fail survives Holm over the level's {family} tested "
                           "criteria depends on the uncommitted p of the profile or field")
            elif c["own_state"] == eq.FAIL and state != eq.FAIL:
                why.append(f"its fail does not survive Holm over the level's {family} tested "
                           "criteria")
            rows.append({k: c[k] for k in ("condition", "criterion", "old_state", "budget",
                                           "old_lo", "old_hi", "lo", "hi", "p_fail")}
                        | {"state": state, "changed": state != c["old_state"],
                           "why": "; ".join(why), "alpha": alpha, "df_rule": df_rule})
    return pd.DataFrame(rows)


def path(study: Study) -> Path:
    return OUT / f"redecided_{study.name}.csv"


def derived(folder: ResultsFolder) -> dict[str, str]:
    """Every committed study re-decided, one table each."""
    return {path(s).name: csv_text(redecide(s)) for s in STUDIES}


#: the README (with rates*.txt of benchmarks/verdict_designs.py) is written by hand
FOLDER = ResultsFolder(OUT, None, "scripts/redecide_issue45.py", derived)


def main(argv=None) -> int:
    return results_command(__doc__, [FOLDER], lambda args: FOLDER, argv)


if __name__ == "__main__":
    sys.exit(main())
