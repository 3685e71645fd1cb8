"""The answer of a study: per sweep group, which CG level and rule meets the error budget,
the error each level is shown to stay within, and at what speedup.

Pure functions of the report's case table (one row per run), its condition table (one row
per sweep group, CG level and rule), the runs' velocity profiles, the workflow's
``accept:`` block (:class:`~ligwf.scene.accept.AcceptSettings`) and the granule control
verdicts (:func:`granule_gates`). The statistics are
:mod:`ligwf.inference.equivalence` (their coverage: ``benchmarks/bench_coverage.py``):

- **signed criteria** (angle of repose in deg, rigid-block share, flowing-layer thickness
  relative to CG1) are the difference of run means CG-n - CG1 with its (1 - 2 alpha)
  interval (``df_rule``'s degrees of freedom), decided by two one-sided tests against
  +-budget: ``pass`` when the interval lies inside, ``fail`` when the two-sided fail test
  rejects, else ``undecided`` (saying which arm's replicas would decide it);
- the **velocity profile** is the relative L2 distance of the mean profiles, less the noise
  of both arms, with one-sided bounds from the noncentral F distribution: ``pass`` when the
  upper bound is within the budget, ``fail`` when the lower bound exceeds it;
- the GSD and field errors keep the analysis' intervals against the tolerance;
- ``not assessed`` (the GSD where the granules did not beat their cohesionless control)
  or ``not measured`` (no value).

The CG1 noise floor no longer widens a budget: each signed criterion says whether its
difference is distinguishable from CG1 seed noise at the replicas run. Family rule: a
level meets the budget when every assessed criterion passes (an intersection-union test,
each at alpha); it fails when a criterion fails after Holm's step-down over every criterion
the level was tested on (:func:`condition_criteria`): each registered criterion
(:func:`ligwf.inference.budget.criteria`) decides itself and gives the p-value of its fail
test (:class:`~ligwf.inference.registry.Decision`), decided or not, so the family's size
does not depend on the outcome; a fail Holm does not keep becomes undecided, planned at the
family's alpha. The alpha, levels and rules travel with the verdict
(``Verdict.statistics``). Every criterion also carries ``bound``: the largest error its
interval allows (the error the level is shown to stay within), so a user with another
budget reads the answer without a rerun. Written by :mod:`ligwf.inference.verdict_records`, shown by
:mod:`ligwf.report.verdict_text`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import pandas as pd

from ligwf.inference import budget
from ligwf.inference import equivalence as eq
from ligwf.study.condition import REFERENCE_CG, Condition
from ligwf.inference.equivalence import FAIL, PASS, UNDECIDED
from ligwf.inference.registry import (NO_DECIDE, NOT_ASSESSED, CriterionResult, Decision, Gate,
                                      LevelData, band)
from ligwf.inference.deciding import decide_text, too_short_note
from ligwf.inference.extrapolated import extrapolated_criteria
from ligwf.inference.verdict_statistics import statistics_record
from ligwf.scene.accept import AcceptSettings
from ligwf.study.group import SweepGroup

#: condition states
MEETS, FAILS = "meets the budget", "fails"


@dataclass(frozen=True)
class ConditionVerdict:
    group: str
    cg: float
    rule: str
    replicas: int
    speedup: float
    speedup_lo: float
    speedup_hi: float
    criteria: tuple[CriterionResult, ...]
    #: runs of either arm too short to show a steady state, and what would fix it
    #: (:func:`ligwf.inference.deciding.too_short_note`; "" when every window starts in time)
    too_short: str = ""

    @property
    def condition(self) -> Condition:
        """The condition this verdict is on (its sweep group, CG level and rule)."""
        return Condition(self.group, self.cg, self.rule)

    @property
    def name(self) -> str:
        return self.condition.name

    @property
    def state(self) -> str:
        """MEETS (every assessed criterion passes), FAILS (one fails), else UNDECIDED."""
        assessed = [c for c in self.criteria if c.assessed]
        if any(c.state == FAIL for c in assessed):
            return FAILS
        if assessed and all(c.state == PASS for c in assessed):
            return MEETS
        return UNDECIDED


@dataclass(frozen=True)
class GroupVerdict:
    group: str
    conditions: tuple[ConditionVerdict, ...]
    sentence: str
    cheapest: str | None = None   # the condition named by the sentence, if one meets


@dataclass(frozen=True)
class Verdict:
    groups: tuple[GroupVerdict, ...]
    accept: dict = field(default_factory=dict)   # the tolerances it was decided with
    #: alpha, interval level, df rule, fail test and family rule it was decided with
    #: (:func:`ligwf.inference.verdict_statistics.statistics_record`; {} in older records)
    statistics: dict = field(default_factory=dict)


def is_control_group(group: str) -> bool:
    """A group of control twins (its swept values hold the control key)."""
    return SweepGroup.parse(group).control is not None


# ------------------------------------------------------------------ groups and the sentence
def _num(v: float) -> str:
    return "–" if not math.isfinite(v) else f"{v:.3g}"


def band_text(value: float, lo: float, hi: float, unit: str = "") -> str:
    """``1.2 [0.5, 2.1] deg``, or ``1.2 (no interval)``."""
    u = f" {unit}" if unit else ""
    if math.isfinite(lo) and math.isfinite(hi):
        return f"{_num(value)} [{_num(lo)}, {_num(hi)}]{u}"
    return f"{_num(value)}{u} (no interval)"


def _speedup(c: ConditionVerdict) -> str:
    return f"speedup {band_text(c.speedup, c.speedup_lo, c.speedup_hi)}"


def _not_in_budget(c: ConditionVerdict) -> str:
    """``; GSD ... not assessed (why); ...`` for the criteria left out of a decision."""
    left = [f"{r.label} {r.note}" for r in c.criteria if not r.assessed]
    return "".join(f"; {x}" for x in left)


def group_sentence(conditions: list[ConditionVerdict]) -> tuple[str, str | None]:
    """The group's one sentence, and the cheapest condition meeting the budget (or None)."""
    if not conditions:
        return "Only CG1 ran in this group: there is no CG level to choose.", None
    by_cost = sorted(conditions, key=lambda c: -c.speedup if math.isfinite(c.speedup) else math.inf)
    meets = [c for c in by_cost if c.state == MEETS]
    if meets:
        best = meets[0]
        text = (f"{best.name} is the cheapest level that meets the budget: "
                f"{_speedup(best)}{_not_in_budget(best)}.")
        cheaper = [c for c in by_cost[:by_cost.index(best)] if c.state == UNDECIDED]
        if cheaper:
            c = cheaper[0]
            first = next(r for r in c.criteria if r.state == UNDECIDED)
            text += (f" {c.name} ({_speedup(c)}) might too: undecided on the {first.label} "
                     f"({first.note}).")
        return text, best.name
    parts = []
    for c in by_cost:
        failed = next((r for r in c.criteria if r.state == FAIL), None)
        if failed is not None:
            parts.append(f"{c.name} fails the {failed.label} first "
                         f"({band_text(failed.value, failed.lo, failed.hi, failed.unit)} "
                         f"beyond the budget {_num(failed.budget)})")
        elif (open_ := [r for r in c.criteria if r.state == UNDECIDED]):
            parts.append(f"{c.name} is undecided on the "
                         + ", ".join(r.label for r in open_)
                         + f" (the {open_[0].label}: {open_[0].note})")
        else:
            parts.append(f"{c.name} was assessed on no criterion{_not_in_budget(c)}")
    verb = "meets" if all(c.state == FAILS for c in conditions) else "is shown to meet"
    return f"No CG level {verb} the whole budget: " + "; ".join(parts) + ".", None


def granule_gates(cases: pd.DataFrame, controls: pd.DataFrame | None) -> dict[str, Gate]:
    """Per sweep group: do its wet CG1 cases' granules (the study's own definition, the
    first row per case of the controls table) beat their cohesionless twins?"""
    groups = sorted(set(cases["group"])) if "group" in cases else []
    if controls is None or controls.empty:
        return {g: Gate(None, "no cohesionless control ran (sweep.controls: [cohesionless]), "
                              "so the granules were never shown to be granules")
                for g in groups}
    own = controls.groupby("case_id", sort=False).head(1)
    group_of = dict(zip(cases["case_id"], cases["group"]))
    gates = {}
    for g in groups:
        rows = own[own["case_id"].map(group_of) == g]
        if rows.empty:
            gates[g] = Gate(None, "no cohesionless control ran in this group")
        elif rows["passes"].astype(bool).all():
            gates[g] = Gate(True)
        else:
            gates[g] = Gate(False, "granules did not beat their cohesionless control")
    return gates


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
    for spec in budget.criteria():
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
        return replace(r, state=UNDECIDED, note=note)
    if r.state in (PASS, FAIL):
        return replace(r, **NO_DECIDE)
    return r


def extrapolated_group(group: str, sub: pd.DataFrame, in_group: pd.DataFrame,
                       accept: AcceptSettings, alpha: float, size_ratio: float,
                       speedups: dict[Condition, float], noise: pd.DataFrame | None = None
                       ) -> GroupVerdict:
    """The verdict of a group without CG1: every CG-n level of a rule with two or more
    levels judged against that rule's extrapolated CG1."""
    out = []
    for _, row in sub.sort_values(["cg", "rule"]).iterrows():
        rule = str(row["rule"])
        runs = in_group[in_group["rule"].astype(str) == rule]
        if runs["cg"].nunique() < 2:
            continue
        results = extrapolated_criteria(accept, runs, float(row["cg"]), size_ratio, alpha)
        speedup = speedups.get(Condition(group, float(row["cg"]), rule), math.nan)
        level = runs[runs["cg"] == float(row["cg"])]
        out.append(ConditionVerdict(group, float(row["cg"]), rule, int(row["replicas"]),
                                    speedup, math.nan, math.nan, results,
                                    too_short_note(level, None, noise)))
    if not out:
        return GroupVerdict(group, (), "No CG1 case in this group and no rule with two CG "
                                       "levels to extrapolate CG1 from: nothing to compare "
                                       "the CG levels with.")
    sentence, cheapest = group_sentence(out)
    return GroupVerdict(group, tuple(out), "No CG1 ran: every level is judged against the "
                        "CG1 value extrapolated from its rule's CG levels (speedups: the "
                        "planner's CG1 cost). " + sentence, cheapest)


def decide(conditions: pd.DataFrame, accept: AcceptSettings,
           gates: dict[str, Gate] | None = None, cases: pd.DataFrame | None = None,
           profiles: dict | None = None, alpha: float = eq.ALPHA,
           noise: pd.DataFrame | None = None, df_rule: str = eq.WELCH,
           size_ratio: float = math.nan, speedups: dict[Condition, float] | None = None
           ) -> Verdict:
    """The verdict of every sweep group of a condition table (control groups left out);
    ``cases`` (one row per run) and ``profiles`` (case id -> mean velocity profile) hold
    the run values the signed and profile criteria are decided on; ``noise`` (by case id,
    :func:`ligwf.inference.planning.noise_table`) what would decide an undecided one and its
    cost; ``alpha`` each test's level and ``df_rule`` its degrees of freedom (a sequential
    study's per-look level, Hsu's conservative df). A group without CG1 is judged against
    the CG1 value extrapolated from its CG-n levels (:mod:`ligwf.inference.extrapolated`;
    ``size_ratio``: the drum's d / D, the model term's scale; ``speedups``: condition
    -> the planner's CG1 cost over the level's, the speedup it reports)."""
    gates, profiles = gates or {}, profiles or {}
    groups = []
    if conditions.empty:
        return Verdict((), accept.model_dump(mode="json"), statistics_record(alpha, df_rule))
    if cases is None:
        cases = pd.DataFrame(columns=["case_id", "group", "cg", "rule"])
    for group, sub in conditions.groupby("group", sort=True):
        group = str(group)
        if is_control_group(group):
            continue
        in_group = cases[cases["group"].astype(str) == group]
        if sub[sub["cg"] == REFERENCE_CG].empty:
            groups.append(extrapolated_group(group, sub, in_group, accept, alpha, size_ratio,
                                             speedups or {}, noise))
            continue
        ref_runs = in_group[in_group["cg"] == REFERENCE_CG]
        gate = gates.get(group, Gate(None, "no cohesionless control ran"))
        out = []
        for _, row in sub[sub["cg"] != REFERENCE_CG].sort_values(["cg", "rule"]).iterrows():
            cond = Condition(group, float(row["cg"]), str(row["rule"]))
            runs = in_group[(in_group["cg"] == cond.cg)
                            & (in_group["rule"].astype(str) == cond.rule)]
            results = condition_criteria(accept, row, runs, ref_runs, profiles, gate, alpha,
                                         noise, df_rule)
            out.append(ConditionVerdict(cond.group, cond.cg, cond.rule,
                                        int(row["replicas"]), *band(row, "speedup_core"),
                                        results, too_short_note(runs, ref_runs, noise)))
        sentence, cheapest = group_sentence(out)
        groups.append(GroupVerdict(group, tuple(out), sentence, cheapest))
    return Verdict(tuple(groups), accept.model_dump(mode="json"),
                   statistics_record(alpha, df_rule))
