"""How one CG-n condition is decided on every criterion of the budget
(:mod:`ligwf.inference.verdict` combines the conditions into the study's answer).

Each registered criterion (:func:`ligwf.inference.budget.criteria`) decides itself and
gives the p-value of its fail test (:class:`~ligwf.inference.registry.Decision`); Holm's
step-down over the fail tests of every tested criterion of the level (each with its own
p-value, decided or not, so the family's size does not depend on the outcome) decides which
fails stand. A fail Holm does not keep becomes undecided, planned at the family's alpha.
The statistics: :mod:`ligwf.inference.equivalence`.
"""

from __future__ import annotations

import dataclasses
import math

import pandas as pd

from ligwf.inference import equivalence as eq
from ligwf.inference.budget import criteria
from ligwf.inference.deciding import decide_text
from ligwf.inference.equivalence import FAIL, PASS, UNDECIDED
from ligwf.inference.registry import (NO_DECIDE, NOT_ASSESSED, CriterionResult, Decision, Gate,
                                      LevelData)
from ligwf.scene.accept import AcceptSettings


def condition_criteria(accept: AcceptSettings, row, runs: pd.DataFrame, ref_runs: pd.DataFrame,
                       profiles: dict, gate: Gate, alpha: float = eq.ALPHA,
                       noise: pd.DataFrame | None = None, df_rule: str = eq.WELCH
                       ) -> tuple[CriterionResult, ...]:
    """Every criterion of the budget for one CG-n condition (``row`` of the condition table,
    ``runs`` its cases, ``ref_runs`` its group's CG1 cases), with Holm's step-down over the
    fail tests of every criterion tested (an interval or bounds): a criterion fails only if
    its fail test survives Holm."""
    level = LevelData(row, runs, ref_runs, profiles, gate, alpha, noise, df_rule)
    decisions: list[Decision] = []
    for spec in criteria():
        tol = accept.tolerance(spec.name)
        if tol is None:
            continue
        if spec.gated and gate.passes is not True:
            decisions.append(Decision(CriterionResult(**spec.base(), state=NOT_ASSESSED,
                                                      note=f"not assessed: {gate.reason}")))
        else:
            decisions.append(spec.decide(spec, tol, level))
    p_fail = [d.p_fail for d in decisions]
    rejected = eq.holm_rejects(p_fail, alpha)
    family = sum(math.isfinite(p) for p in p_fail)
    out = [d.replan(alpha / family) if d.result.state == FAIL and not ok and d.replan
           else d.result for d, ok in zip(decisions, rejected)]
    return tuple(after_holm(r, ok, family) for r, ok in zip(out, rejected))


def after_holm(r: CriterionResult, rejected: bool, family: int) -> CriterionResult:
    """A fail that Holm's step-down does not keep becomes undecided (saying what would
    decide it); a decided criterion carries no decide option."""
    if r.state == FAIL and not rejected:
        note = "; ".join(p for p in (f"outside the budget on its own, not after Holm over "
                                     f"the level's {family} tested criteria", decide_text(r),
                                     r.note) if p)
        return dataclasses.replace(r, state=UNDECIDED, note=note)
    if r.state in (PASS, FAIL):
        return dataclasses.replace(r, **NO_DECIDE)
    return r
