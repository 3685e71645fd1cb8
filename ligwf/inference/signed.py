"""Signed criteria: the difference of run means CG-n - CG1 (relative to the CG1 mean for a
:data:`~ligwf.inference.registry.RELATIVE` estimate) with its (1 - 2 alpha) t interval
(the level's df rule: Welch's for equal arms, Hsu's for unequal ones or sequential looks),
passed by two one-sided tests against +-budget and failed by a two-sided fail test
(:mod:`ligwf.inference.equivalence`); a share whose runs all read 0 in an arm is bounded
over runs (:mod:`ligwf.inference.shares`). What would decide it:
:func:`ligwf.inference.deciding.signed_plan` (the criterion's ``plan``).
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pandas as pd

from ligwf.inference import equivalence as eq
from ligwf.inference import planning, sampling, shares
from ligwf.inference.equivalence import UNDECIDED
from ligwf.inference.registry import (NO_DECIDE, NOT_MEASURED, RELATIVE, Criterion,
                                      CriterionResult, Decision, LevelData)


def per_run(runs: pd.DataFrame | None, column: str) -> np.ndarray:
    """The runs' values of a case-table column (empty without it)."""
    return pd.to_numeric(runs[column], errors="coerce").to_numpy(float) if (
        runs is not None and column in runs) else np.array([])


def arm(runs: pd.DataFrame | None, column: str, noise: pd.DataFrame | None,
        scale: float = 1.0) -> sampling.ArmRuns:
    """The runs of one arm with their noise and prices (noise table rows by case id)."""
    values = per_run(runs, column)
    ids = list(runs["case_id"]) if runs is not None and "case_id" in runs else []
    if noise is None or noise.empty or len(ids) != len(values):
        return sampling.arm(values * scale)

    def col(name: str) -> np.ndarray:
        if name not in noise:
            return np.full(len(ids), math.nan)
        return np.array([float(noise[name].get(i, math.nan)) for i in ids])

    share = col(planning.STEADY_SHARE)
    share = float(np.nanmean(share)) if np.isfinite(share).any() else 0.75
    return sampling.arm(values, col(planning.within_column(column)),
                        col(planning.WINDOW), steady_share=share,
                        replica_core_seconds=float(np.nanmean(col(planning.REPLICA_COST))),
                        production_core_seconds=float(np.nanmean(
                            col(planning.PRODUCTION_COST))),
                        least_extension=float(np.nanmax(col(planning.LEAST_EXTENSION),
                                                        initial=0.0))).scaled(scale)


def decide_signed(spec: Criterion, tolerance: float, level: LevelData) -> Decision:
    """A signed criterion on one level, with the p-value of its fail test (for Holm over
    the level) and, for a fail Holm may not keep, its plan at the family's alpha."""
    x = arm(level.runs, spec.metric, level.noise)
    y = arm(level.ref_runs, spec.metric, level.noise)
    result, p_fail = signed_result(spec, tolerance, x, y, level.alpha, level.df_rule)
    return Decision(result, p_fail,
                    lambda alpha: holm_replan(spec, result, x, y, alpha, level.df_rule))


def signed_result(spec: Criterion, tolerance: float, x: sampling.ArmRuns,
                  y: sampling.ArmRuns, alpha: float, df_rule: str = eq.WELCH
                  ) -> tuple[CriterionResult, float]:
    """The difference of run means CG-n - CG1 (relative to the CG1 mean for RELATIVE), two
    one-sided tests at alpha. Returns the result and the p-value of its fail test."""
    base = spec.base(tolerance)
    scale = 1.0
    if spec.estimate == RELATIVE:
        ref = float(np.nanmean(y.values)) if np.isfinite(y.values).any() else math.nan
        if not ref > 0:
            return CriterionResult(**base, state=NOT_MEASURED, note=(
                f"not measured: the CG1 {spec.label} is 0: no relative difference")), math.nan
        scale = 1.0 / ref
    e = eq.scaled(eq.difference_estimate(x.values, y.values, alpha, df_rule), scale)
    if not math.isfinite(e.value):
        return CriterionResult(**base, state=NOT_MEASURED,
                               note=f"not measured: no {spec.metric} value"), math.nan
    zero = shares.share_test(x.values, y.values, tolerance, alpha) if spec.share else None
    if zero is not None:
        return all_zero(base, zero, x, y, tolerance, alpha)
    test = eq.equivalence(e, tolerance, alpha)
    noise = eq.difference_estimate(x.values, y.values, alpha / 2, df_rule)
    vs_noise = ("" if not noise.has_interval else
                "differs from CG1 beyond seed noise" if (noise.lo > 0 or noise.hi < 0)
                else "indistinguishable from CG1 seed noise at these replicas")
    note, decide = vs_noise, {}
    if test.state == UNDECIDED and spec.plan is not None:
        decide, how = spec.plan(x.scaled(scale), y.scaled(scale), e, tolerance, alpha,
                                spec.unit, df_rule)
        note = "; ".join(part for part in (how, vs_noise) if part)
    bound = max(abs(e.lo), abs(e.hi)) if e.has_interval else math.nan
    return CriterionResult(**base, state=test.state, value=e.value, lo=e.lo, hi=e.hi,
                           bound=bound, note=note, **decide), test.p_fail


def all_zero(base: dict, zero: tuple[eq.Estimate, eq.Test], x: sampling.ArmRuns,
             y: sampling.ArmRuns, tolerance: float, alpha: float
             ) -> tuple[CriterionResult, float]:
    """A share whose runs all read 0 in an arm (:func:`shares.share_test`): the zero arm's mean
    is bounded over its runs (rule of three), never by a variance of 0."""
    e, test = zero
    arms = [f"{name} ({n} runs) <= {shares.zero_arm_bound(n, alpha):.3g}"
            for name, v, n in (("CG-n", x.values, x.n), ("CG1", y.values, y.n))
            if n and np.all(np.asarray(v)[np.isfinite(v)] == 0)]
    need = math.ceil(math.log(alpha) / math.log(1.0 - tolerance)) if 0 < tolerance < 1 else 0
    note = (f"every run of {' and '.join(a.split(' (')[0] for a in arms)} reads 0: its mean "
            f"share is bounded over runs, not frames (rule of three, one-sided "
            f"{100 * (1 - alpha):.3g} %: {'; '.join(arms)})")
    if test.state == UNDECIDED and need:
        note += (f"; {need} all-zero runs of an arm would bound it within the budget "
                 f"{tolerance:g}")
    bound = max(abs(e.lo), abs(e.hi))
    return CriterionResult(**base, state=test.state, value=e.value, lo=e.lo, hi=e.hi,
                           bound=bound, note=note), test.p_fail


def holm_replan(spec: Criterion, r: CriterionResult, x: sampling.ArmRuns, y: sampling.ArmRuns,
                alpha: float, df_rule: str) -> CriterionResult:
    """What would decide a signed fail that Holm's step-down did not keep: the fail test
    must pass at ``alpha`` (the level's alpha over its family size, which Holm's first step
    asks and which is enough at every later step), so the cheapest option is planned at
    that level, not at the per-test alpha where the fail already holds."""
    if spec.plan is None:
        return r
    scale = 1.0
    if spec.estimate == RELATIVE:
        ref = float(np.nanmean(y.values))
        scale = 1.0 / ref if ref > 0 else math.nan
    e = eq.scaled(eq.difference_estimate(x.values, y.values, alpha, df_rule), scale)
    fields, _ = spec.plan(x.scaled(scale), y.scaled(scale), e, r.budget, alpha, r.unit,
                          df_rule)
    return dataclasses.replace(r, **(NO_DECIDE | fields))
