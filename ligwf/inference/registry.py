"""The criteria of the verdict's budget: one registry, one declaration per criterion.

A criterion (:class:`Criterion`) declares

* its **budget key**: the ``accept:`` field holding its tolerance (the built-in keys are
  :class:`~ligwf.scene.accept.AcceptSettings` fields; a plug-in brings its own
  :class:`~ligwf.scene.accept.Budget`, added to the ``accept:`` block when it registers);
* its **metric**: the case-table (signed) or condition-table (error) column it reads;
* its **estimate**: how it reads the tables (:data:`SIGNED` difference of run means,
  :data:`RELATIVE` to the CG1 mean, :data:`PROFILE` noise-corrected distance, :data:`ERROR`
  the analysis' own interval);
* its **decision**: ``decide(criterion, tolerance, level) -> Decision`` -- the state, the
  interval, the bound it is shown within, and the p-value of its fail test for Holm's
  step-down over the level (:func:`ligwf.inference.verdict.condition_criteria`);
* its **plan**: what would decide it when undecided (:mod:`ligwf.inference.deciding`).

The built-in criteria are registered by :mod:`ligwf.inference.budget` (each reader of the
registry asks :func:`ligwf.inference.budget.criteria`); a plug-in criterion is one module
that defines its ``decide`` and calls :func:`register` (``tests/inference/test_toy_criterion.py``
registers one from the test folder and finds it in the ``accept:`` block, the verdict, its
record and the data dictionary).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable

import pandas as pd

from ligwf.inference.equivalence import ALPHA, FAIL, PASS, UNDECIDED, WELCH
from ligwf.scene.accept import AcceptSettings, Budget, register_budget

#: the states of a criterion beside the tests' own (pass, fail, undecided)
NOT_ASSESSED, NOT_MEASURED = "not assessed", "not measured"

#: how a criterion reads the tables (its estimate)
SIGNED, RELATIVE, PROFILE, ERROR = "signed", "relative difference", "profile", "error"
#: the estimates that are a difference of run means (two one-sided tests, extrapolable)
DIFFERENCES = (SIGNED, RELATIVE)


@dataclass(frozen=True)
class Gate:
    """Whether the granules of a sweep group beat their cohesionless control (None: no
    control ran), and why not."""

    passes: bool | None
    reason: str = ""


@dataclass(frozen=True)
class CriterionResult:
    name: str
    label: str
    unit: str
    state: str
    value: float = math.nan
    lo: float = math.nan
    hi: float = math.nan
    budget: float = math.nan
    budget_source: str = ""   # "tolerance"
    note: str = ""            # what would decide it, or why it is not assessed
    bound: float = math.nan   # the largest |error| its interval allows (shown within)
    #: the cheapest way to decide it (undecided only, :mod:`ligwf.inference.sampling`):
    #: extend | replicas, on which arm, how much (s of production per run, or runs), at
    #: what cost (core-hours, the planner's rates) and the half-width it predicts
    decide_by: str = ""
    decide_arm: str = ""
    decide_amount: float = math.nan       # s of production per run, or CG-n replicas
    decide_amount_cg1: float = math.nan   # CG1 replicas (replicas only)
    decide_core_hours: float = math.nan
    decide_half_width: float = math.nan
    #: what a round of a sequential study does instead (:mod:`ligwf.pipeline.rounds`): the
    #: cheapest way to HALVE the half-width, which does not depend on the measured
    #: difference (amounts chosen from the difference bias the later looks' tests)
    round_by: str = ""
    round_arm: str = ""
    round_amount: float = math.nan
    round_amount_cg1: float = math.nan
    round_core_hours: float = math.nan

    @property
    def assessed(self) -> bool:
        return self.state in (PASS, FAIL, UNDECIDED)


#: a result's "what would decide it" fields, emptied (a decided criterion carries none)
NO_DECIDE = dict(decide_by="", decide_arm="", decide_amount=math.nan,
                 decide_amount_cg1=math.nan, decide_core_hours=math.nan,
                 decide_half_width=math.nan, round_by="", round_arm="", round_amount=math.nan,
                 round_amount_cg1=math.nan, round_core_hours=math.nan)


@dataclass(frozen=True)
class LevelData:
    """What one CG-n condition is decided on: ``row`` of the condition table, ``runs`` its
    cases and ``ref_runs`` its group's CG1 cases (case-table rows), the runs' velocity
    profiles by case id, the granule gate, each test's ``alpha``, the noise table (the runs'
    noise and prices, for what would decide) and the degrees-of-freedom rule."""

    row: pd.Series | None
    runs: pd.DataFrame | None
    ref_runs: pd.DataFrame | None
    profiles: dict
    gate: Gate
    alpha: float = ALPHA
    noise: pd.DataFrame | None = None
    df_rule: str = WELCH


@dataclass(frozen=True)
class Decision:
    """A criterion decided on one level: its result, the p-value of its fail test (nan: not
    tested; every tested criterion enters Holm's family with its own), and for a fail that
    Holm's step-down may not keep, what would decide it at the family's alpha."""

    result: CriterionResult
    p_fail: float = math.nan
    replan: Callable[[float], CriterionResult] | None = None


@dataclass(frozen=True)
class Criterion:
    """One criterion of the budget (see the module's docstring for the fields' meaning)."""

    name: str           # the budget key: the accept: field holding its tolerance
    label: str
    unit: str           # of the value and the budget ("" for a ratio)
    metric: str         # the case-table (signed) or condition-table (error) column it reads
    estimate: str       # SIGNED | RELATIVE | PROFILE | ERROR
    decide: Callable[["Criterion", float, LevelData], Decision]
    plan: Callable[..., object] | None = None   # what would decide it (deciding.*_plan)
    gated: bool = False    # only where the granules beat their cohesionless control
    share: bool = False    # a share in [0, 1] per run: an all-zero arm gets a bound over runs
    budget: Budget | None = None   # a plug-in's accept: field (None: a built-in field)

    def base(self, tolerance: float = math.nan) -> dict:
        """The fields every result of this criterion carries."""
        out = dict(name=self.name, label=self.label, unit=self.unit)
        return out | (dict(budget=tolerance, budget_source="tolerance")
                      if math.isfinite(tolerance) else {})

    @property
    def description(self) -> str:
        """What its tolerance means (the ``accept:`` field's description)."""
        if self.budget is not None:
            return self.budget.description
        return AcceptSettings.model_fields[self.name].description or ""

    @property
    def default(self) -> float | None:
        """Its tolerance when the ``accept:`` block does not set it."""
        if self.budget is not None:
            return self.budget.default
        return AcceptSettings.model_fields[self.name].default


_REGISTRY: dict[str, Criterion] = {}


def register(criterion: Criterion) -> None:
    """Add a criterion to the budget (after the ones registered before it: the order
    "fails first" and the tables follow). A built-in names an ``accept:`` field; a plug-in
    brings its :class:`Budget`, which the ``accept:`` block then accepts."""
    if criterion.name in _REGISTRY:
        raise ValueError(f"criterion {criterion.name!r} is registered already")
    if criterion.budget is None:
        if criterion.name not in AcceptSettings.model_fields:
            raise ValueError(f"criterion {criterion.name!r}: no accept: field of that name "
                             "(a plug-in criterion declares its Budget)")
    elif criterion.budget.key != criterion.name:
        raise ValueError(f"criterion {criterion.name!r} declares budget "
                         f"{criterion.budget.key!r}")
    else:
        register_budget(criterion.budget)
    _REGISTRY[criterion.name] = criterion


def unregister(name: str) -> None:
    """Take a plug-in criterion out again (its ``accept:`` field too); for tests."""
    criterion = _REGISTRY.pop(name)
    if criterion.budget is not None:
        register_budget(criterion.budget, remove=True)


def registered() -> tuple[Criterion, ...]:
    """Every criterion registered so far, in registration order."""
    return tuple(_REGISTRY.values())


def row_value(row, col: str) -> float:
    v = row.get(col, math.nan) if row is not None else math.nan
    try:
        v = float(v)
    except (TypeError, ValueError):
        return math.nan
    return v


def band(row, col: str) -> tuple[float, float, float]:
    """(value, lo, hi); lo/hi nan without a replica interval."""
    return row_value(row, col), row_value(row, f"{col}_lo"), row_value(row, f"{col}_hi")
