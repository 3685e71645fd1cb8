"""The answer of a study: per sweep group, which CG level and rule meets the error budget,
the error each level is shown to stay within, and at what speedup.

Pure functions of the report's case table (one row per run), its condition table (one row
per sweep group, CG level and rule), the runs' velocity profiles, the workflow's
``accept:`` block (:class:`~ligwf.scene.accept.AcceptSettings`) and the granule control
verdicts (:func:`granule_gates`). The statistics are
:mod:`ligwf.analysis.records.equivalence` (their coverage: ``benchmarks/bench_coverage.py``):

- **signed criteria** (angle of repose in deg, rigid-block share, flowing-layer thickness
  relative to CG1) are the difference of run means CG-n - CG1 with Welch's interval, decided
  by two one-sided tests against +-budget: ``pass`` when the 90 % interval lies inside,
  ``fail`` when it lies wholly outside, else ``undecided`` (saying which arm's replicas
  would decide it);
- the **velocity profile** is the relative L2 distance of the mean profiles, less the noise
  of both arms, with bin-wise (Bonferroni) bounds: ``pass`` when the upper bound is within
  the budget, ``fail`` when the lower bound exceeds it;
- the GSD and field errors keep the analysis' intervals against the tolerance;
- ``not assessed`` (the GSD where the granules did not beat their cohesionless control)
  or ``not measured`` (no value).

The CG1 noise floor no longer widens a budget: each signed criterion says whether its
difference is distinguishable from CG1 seed noise at the replicas run. Family rule: a
level meets the budget when every assessed criterion passes (an intersection-union test,
each at alpha); it fails when a criterion fails after Holm's step-down over the level's
criteria. Every criterion also carries ``bound``: the largest error its interval allows
(the error the level is shown to stay within), so a user with another budget reads the
answer without a rerun. Written by :mod:`ligwf.report.verdict_records`, shown by
:mod:`ligwf.report.verdict_text`.
"""

from __future__ import annotations

import dataclasses
import json
import math
from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from ligwf.analysis.records import equivalence as eq
from ligwf.analysis.records.conditions import REFERENCE_CG, Condition
from ligwf.scene.accept import AcceptSettings
from ligwf.scene.workflow import CONTROL_KEY

PASS, FAIL, UNDECIDED = "pass", "fail", "undecided"
NOT_ASSESSED, NOT_MEASURED = "not assessed", "not measured"
#: condition states
MEETS, FAILS = "meets the budget", "fails"

#: how a criterion reads the tables
SIGNED, RELATIVE, PROFILE, ERROR = "signed", "relative difference", "profile", "error"


@dataclass(frozen=True)
class CriterionSpec:
    """One criterion of the budget: its ``accept:`` field, what it reads and how."""

    name: str           # the AcceptSettings field (its tolerance)
    label: str
    unit: str           # of the value and the budget ("" for a ratio)
    column: str         # the case-table (signed) or condition-table (error) column it reads
    kind: str           # SIGNED | RELATIVE (to the CG1 mean) | PROFILE | ERROR
    gated: bool = False    # only where the granules beat their control


#: The budget's criteria, in the order "fails first" refers to.
CRITERIA = (
    CriterionSpec("angle_deg", "angle of repose", "deg", "angle_of_repose", SIGNED),
    CriterionSpec("profile_error", "velocity profile", "", "profile_error", PROFILE),
    CriterionSpec("rigid_share", "rigid-block frames", "", "rigid_frame_share", SIGNED),
    CriterionSpec("flowing_layer", "flowing layer", "", "flowing_layer_thickness_mean", RELATIVE),
    CriterionSpec("gsd_error", "GSD", "", "gsd_error_all", ERROR, gated=True),
    CriterionSpec("field_error", "continuum fields", "", "field_error", ERROR),
)


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

    @property
    def assessed(self) -> bool:
        return self.state in (PASS, FAIL, UNDECIDED)


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

    @property
    def name(self) -> str:
        return Condition(self.group, self.cg, self.rule).name

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


# ------------------------------------------------------------------ reading the table
def _f(row, col: str) -> float:
    v = row.get(col, math.nan) if row is not None else math.nan
    try:
        v = float(v)
    except (TypeError, ValueError):
        return math.nan
    return v


def _band(row, col: str) -> tuple[float, float, float]:
    """(value, lo, hi); lo/hi nan without a replica interval."""
    return _f(row, col), _f(row, f"{col}_lo"), _f(row, f"{col}_hi")


def is_control_group(group: str) -> bool:
    """A group of control twins (its swept values hold the control key)."""
    try:
        varied = json.loads(group)
    except (TypeError, ValueError):
        return False
    return isinstance(varied, dict) and CONTROL_KEY in varied


# ------------------------------------------------------------------ deciding one criterion
def _state(test_state: str) -> str:
    return {eq.PASS: PASS, eq.FAIL: FAIL}.get(test_state, UNDECIDED)


def _per_run(runs: pd.DataFrame, column: str) -> np.ndarray:
    return pd.to_numeric(runs[column], errors="coerce").to_numpy(float) if (
        runs is not None and column in runs) else np.array([])


def _replica_note(x: np.ndarray, y: np.ndarray, budget: float, alpha: float,
                  scale: float = 1.0) -> str:
    """What would decide an undecided signed criterion: replicas of the arm that
    dominates the width (from the measured variances)."""
    if len(x) < 2 or len(y) < 2:
        who = "CG-n" if len(x) < 2 else "CG1"
        return f"{who} has one run: no variance, no interval (run at least 2 replicas)"
    need = eq.replicas_to_decide(x * scale, y * scale, budget, alpha)
    if need is None:
        return ("the difference sits near the budget for its spread: over 64 replicas of "
                "either arm would be needed")
    arm, n = need
    return f"about {n} {arm} replicas would decide (the {arm} scatter dominates the width)"


def _signed(spec: CriterionSpec, tolerance: float, x: np.ndarray, y: np.ndarray,
            alpha: float) -> tuple[CriterionResult, float]:
    """A signed criterion: the difference of run means CG-n - CG1 (relative to the CG1
    mean for RELATIVE), two one-sided tests at alpha. Returns the result and the p-value
    of its fail test (for Holm over the level)."""
    base = dict(name=spec.name, label=spec.label, unit=spec.unit, budget=tolerance,
                budget_source="tolerance")
    scale = 1.0
    if spec.kind == RELATIVE:
        ref = float(np.nanmean(y)) if np.isfinite(y).any() else math.nan
        if not ref > 0:
            return CriterionResult(**base, state=NOT_MEASURED, note=(
                f"not measured: the CG1 {spec.label} is 0: no relative difference")), math.nan
        scale = 1.0 / ref
    e = eq.scaled(eq.difference_estimate(x, y, alpha), scale)
    if not math.isfinite(e.value):
        return CriterionResult(**base, state=NOT_MEASURED,
                               note=f"not measured: no {spec.column} value"), math.nan
    test = eq.equivalence(e, tolerance, alpha)
    noise = eq.difference_estimate(x, y, alpha / 2)
    vs_noise = ("" if not noise.has_interval else
                "differs from CG1 beyond seed noise" if (noise.lo > 0 or noise.hi < 0)
                else "indistinguishable from CG1 seed noise at these replicas")
    note = vs_noise
    if test.state == eq.UNDECIDED:
        note = "; ".join(x for x in (_replica_note(x, y, tolerance, alpha, scale), vs_noise) if x)
    bound = max(abs(e.lo), abs(e.hi)) if e.has_interval else math.nan
    return CriterionResult(**base, state=_state(test.state), value=e.value, lo=e.lo, hi=e.hi,
                           bound=bound, note=note), test.p_fail


def _norm(spec: CriterionSpec, tolerance: float, x: np.ndarray, y: np.ndarray,
          alpha: float) -> CriterionResult:
    """The velocity profile: the noise-corrected relative L2 distance between the arms'
    mean profiles, decided by its bin-wise bounds."""
    base = dict(name=spec.name, label=spec.label, unit=spec.unit, budget=tolerance,
                budget_source="tolerance")
    e = eq.norm_estimate(x, y, alpha)
    if not math.isfinite(e.value):
        return CriterionResult(**base, state=NOT_MEASURED, note="not measured: no profiles")
    state = _state(eq.norm_decision(e, tolerance))
    note = (f"raw distance {e.raw:.3g} before the noise of both arms is taken off"
            if state != UNDECIDED else
            f"raw distance {e.raw:.3g}; the bin-wise bounds [{e.lo:.3g}, {e.hi:.3g}] straddle "
            "the budget: more replicas of both arms narrow them")
    if not e.has_interval:
        note = "an arm has one run: no variance, no bounds (run at least 2 replicas)"
    return CriterionResult(**base, state=state, value=e.value, lo=e.lo, hi=e.hi, bound=e.hi,
                           note=note)


def _legacy(spec: CriterionSpec, tolerance: float, row) -> CriterionResult:
    """GSD and field errors: their interval from the analysis against the tolerance."""
    base = dict(name=spec.name, label=spec.label, unit=spec.unit, budget=tolerance,
                budget_source="tolerance")
    value, lo, hi = _band(row, spec.column)
    if not math.isfinite(value):
        return CriterionResult(**base, state=NOT_MEASURED,
                               note=f"not measured: no {spec.column} value for this condition")
    if not (math.isfinite(lo) and math.isfinite(hi)):
        return CriterionResult(**base, state=UNDECIDED, value=value,
                               note="no interval (add replicas)")
    state = PASS if hi <= tolerance else FAIL if lo > tolerance else UNDECIDED
    return CriterionResult(**base, state=state, value=value, lo=lo, hi=hi, bound=hi,
                           note="" if state != UNDECIDED else "more replicas of both arms")


def condition_criteria(accept: AcceptSettings, row, runs: pd.DataFrame, ref_runs: pd.DataFrame,
                       profiles: dict, gate: Gate, alpha: float = eq.ALPHA
                       ) -> tuple[CriterionResult, ...]:
    """Every criterion of the budget for one CG-n condition (``row`` of the condition table,
    ``runs`` its cases, ``ref_runs`` its group's CG1 cases), with Holm's step-down over the
    level's fail tests: a criterion fails only if its fail test survives Holm."""
    out, p_fail = [], []
    for spec in CRITERIA:
        tol = getattr(accept, spec.name)
        if tol is None:
            continue
        base = dict(name=spec.name, label=spec.label, unit=spec.unit)
        if spec.gated and gate.passes is not True:
            out.append(CriterionResult(**base, state=NOT_ASSESSED,
                                       note=f"not assessed: {gate.reason}"))
            p_fail.append(math.nan)
        elif spec.kind in (SIGNED, RELATIVE):
            r, p = _signed(spec, tol, _per_run(runs, spec.column),
                           _per_run(ref_runs, spec.column), alpha)
            out.append(r)
            p_fail.append(p)
        elif spec.kind == PROFILE:
            x = [profiles.get(c) for c in runs["case_id"]] if runs is not None else []
            y = [profiles.get(c) for c in ref_runs["case_id"]] if ref_runs is not None else []
            try:
                xa = np.array([p for p in x if p is not None and len(p)], dtype=float)
                ya = np.array([p for p in y if p is not None and len(p)], dtype=float)
            except ValueError:
                xa = ya = np.array([])
            out.append(_norm(spec, tol, xa, ya, alpha))
            p_fail.append(0.0 if out[-1].state == FAIL else math.nan)
        elif spec.column not in row.index:
            out.append(CriterionResult(**base, state=NOT_MEASURED,
                                       note=f"not measured: the study has no {spec.column}"))
            p_fail.append(math.nan)
        else:
            out.append(_legacy(spec, tol, row))
            p_fail.append(0.0 if out[-1].state == FAIL else math.nan)
    rejected = eq.holm_rejects(p_fail, alpha)
    return tuple(r if r.state != FAIL or ok else dataclasses.replace(
        r, state=UNDECIDED, note=(f"outside the budget on its own, not after Holm over the "
                                  f"level's {len(out)} criteria; " + r.note).rstrip("; "))
                 for r, ok in zip(out, rejected))


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


def decide(conditions: pd.DataFrame, accept: AcceptSettings,
           gates: dict[str, Gate] | None = None, cases: pd.DataFrame | None = None,
           profiles: dict | None = None, alpha: float = eq.ALPHA) -> Verdict:
    """The verdict of every sweep group of a condition table (control groups left out);
    ``cases`` (one row per run) and ``profiles`` (case id -> mean velocity profile) hold
    the run values the signed and profile criteria are decided on."""
    gates, profiles = gates or {}, profiles or {}
    groups = []
    if conditions.empty:
        return Verdict((), accept.model_dump(mode="json"))
    if cases is None:
        cases = pd.DataFrame(columns=["case_id", "group", "cg", "rule"])
    for group, sub in conditions.groupby("group", sort=True):
        group = str(group)
        if is_control_group(group):
            continue
        if sub[sub["cg"] == REFERENCE_CG].empty:
            groups.append(GroupVerdict(group, (), "No CG1 case in this group: nothing to "
                                                  "compare the CG levels with."))
            continue
        in_group = cases[cases["group"].astype(str) == group]
        ref_runs = in_group[in_group["cg"] == REFERENCE_CG]
        gate = gates.get(group, Gate(None, "no cohesionless control ran"))
        out = []
        for _, row in sub[sub["cg"] != REFERENCE_CG].sort_values(["cg", "rule"]).iterrows():
            runs = in_group[(in_group["cg"] == row["cg"])
                            & (in_group["rule"].astype(str) == str(row["rule"]))]
            results = condition_criteria(accept, row, runs, ref_runs, profiles, gate, alpha)
            out.append(ConditionVerdict(group, float(row["cg"]), str(row["rule"]),
                                        int(row["replicas"]), *_band(row, "speedup_core"),
                                        results))
        sentence, cheapest = group_sentence(out)
        groups.append(GroupVerdict(group, tuple(out), sentence, cheapest))
    return Verdict(tuple(groups), accept.model_dump(mode="json"))
