"""The verdict of a sweep without CG1: each CG-n level judged against the CG1 value
extrapolated from the levels of its rule (:mod:`ligwf.inference.extrapolation`).

Signed criteria (angle of repose, rigid-block share, flowing layer relative to CG1) are the
contrast CG-n - extrapolated CG1 of the level means (the level judged is part of its own
reference), its interval carrying the levels' run-to-run noise and the model term, decided
by the same two one-sided tests as against a real CG1 and the same Holm step-down over the
level's tested criteria. A criterion whose levels fail the lack-of-fit check is not
assessed ("the rule does not extrapolate", with the numbers); the velocity profile, the
fields and the GSD are norms with no signed value to extrapolate: they are judged only
against a real CG1, and say so.
"""

from __future__ import annotations

import dataclasses
import math

import pandas as pd

from ligwf.inference import equivalence as eq
from ligwf.inference import sampling
from ligwf.inference.equivalence import FAIL, UNDECIDED
from ligwf.inference import extrapolation as ex
from ligwf.inference.reference import level_values, slope_scale
from ligwf.inference.budget import criteria
from ligwf.inference.registry import (DIFFERENCES, NOT_ASSESSED, NOT_MEASURED, RELATIVE,
                                      CriterionResult)
from ligwf.scene.accept import AcceptSettings

#: the note of a criterion with no signed value to extrapolate
NORM_NOTE = ("not assessed: a norm against CG1 (no signed value to extrapolate); judged "
             "only against a real CG1 run")


def _signed(spec, tolerance: float, runs: pd.DataFrame, cg: float, ratio: float,
            alpha: float) -> tuple[CriterionResult, float]:
    """One signed criterion of level ``cg`` against the extrapolated CG1 (and its fail
    test's p-value for Holm)."""
    base = dict(name=spec.name, label=spec.label, unit=spec.unit, budget=tolerance,
                budget_source="tolerance")
    values = level_values(runs, spec.metric)
    scale_b = slope_scale(spec.metric, ratio)
    e = ex.extrapolate(values, ratio, alpha, slope_scale=scale_b)
    if not math.isfinite(e.value):
        return CriterionResult(**base, state=NOT_MEASURED, note=(
            f"not measured: fewer than two CG levels with a {spec.metric} value")), math.nan
    where = (f"against CG1 extrapolated from CG{'/'.join(f'{n:g}' for n in e.levels)} "
             f"({e.value:.3g}, {e.form_text})")
    if e.form == ex.REJECTED:
        return CriterionResult(**base, state=NOT_ASSESSED, note=(
            f"not assessed: the rule does not extrapolate on the {spec.label}: "
            f"{e.form_text}")), math.nan
    d = ex.level_difference(values, cg, ratio, alpha, slope_scale=scale_b)
    if spec.estimate == RELATIVE:
        if not e.value > 0:
            return CriterionResult(**base, state=NOT_MEASURED, note=(
                f"not measured: the extrapolated CG1 {spec.label} is not positive")), math.nan
        d = eq.scaled(d, 1.0 / e.value)
    if not d.has_interval:
        return CriterionResult(**base, state=UNDECIDED, value=d.value, note=(
            f"{where}; a level has one run: no interval (run at least 2 replicas a level)")
        ), math.nan
    if not d.se > 0:
        # every run of every level reads the same value (a share of 0 everywhere): no
        # run-to-run variance and no slope, so a zero-width interval would be false precision
        return CriterionResult(**base, state=UNDECIDED, value=d.value, note=(
            f"{where}; every run at every level reads {d.value:.3g}: no run-to-run "
            "variance to bound it by (more replicas at every level)")), math.nan
    test = eq.equivalence(d, tolerance, alpha)
    note, rounds = where, {}
    if test.state == UNDECIDED:
        note = (f"{where}; more replicas at every level narrow it (the noise), more levels "
                "or a finer one shrink the model term")
        # a sequential study's round (--until-decided): double this level's runs (the
        # level judged weighs most in its own contrast; --every-level doubles them all)
        n_runs = int(sum(len(v) for k, v in values.items() if float(k) == float(cg)))
        rounds = dict(round_by=sampling.REPLICAS, round_arm="CG-n",
                      round_amount=float(max(n_runs, 1)))
    return CriterionResult(**base, state=test.state, value=d.value, lo=d.lo, hi=d.hi,
                           bound=max(abs(d.lo), abs(d.hi)), note=note, **rounds), test.p_fail


def extrapolated_criteria(accept: AcceptSettings, runs: pd.DataFrame, cg: float,
                          ratio: float, alpha: float = eq.ALPHA
                          ) -> tuple[CriterionResult, ...]:
    """Every criterion of the budget for CG level ``cg`` of one rule (``runs``: that rule's
    CG-n runs at every level), with Holm's step-down over the level's tested criteria."""
    out, p_fail = [], []
    for spec in criteria():
        tol = accept.tolerance(spec.name)
        if tol is None:
            continue
        if spec.estimate in DIFFERENCES:
            r, p = _signed(spec, tol, runs, cg, ratio, alpha)
        else:
            r, p = CriterionResult(name=spec.name, label=spec.label, unit=spec.unit,
                                   state=NOT_ASSESSED, budget=tol, note=NORM_NOTE), math.nan
        out.append(r)
        p_fail.append(p)
    rejected = eq.holm_rejects(p_fail, alpha)
    family = sum(math.isfinite(p) for p in p_fail)
    return tuple(
        dataclasses.replace(r, state=UNDECIDED, note=(
            f"outside the budget on its own, not after Holm over the level's {family} "
            f"tested criteria; {r.note}")) if r.state == FAIL and not ok else r
        for r, ok in zip(out, rejected))

