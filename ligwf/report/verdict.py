"""The answer of a study: per sweep group, which CG level and rule meets the error budget,
and at what speedup.

Pure functions of the report's condition table (:mod:`ligwf.report.tables`, one row per
sweep group, CG level and rule; every metric ``m`` with ``m_lo``/``m_hi``/``m_se``, every
error also ``m_floor``), the workflow's ``accept:`` block
(:class:`~ligwf.scene.accept.AcceptSettings`) and the granule control verdicts
(:func:`granule_gates`). Each criterion of a CG-n condition is decided by its 95 %
interval [lo, hi] against its budget (the tolerance, or for an error with a CG1 noise
floor ``max(tolerance, floor)``):

- ``pass`` when the whole interval lies within the budget (hi <= budget),
- ``fail`` when the whole interval lies outside it (lo > budget),
- ``undecided`` otherwise (or with one CG-n replica: no interval), saying what would
  decide it (the CG1 replicas of :func:`ligwf.report.uncertainty.replicas_to_decide`),
- ``not assessed`` (the GSD where the granules did not beat their cohesionless control:
  their sizes then measure the bed's tiling) or ``not measured`` (no value in the table).

A condition meets the budget when every criterion it was assessed on passes. The group's
sentence names the cheapest condition (largest speedup) that meets it, or says that none
does and, per condition, the first criterion (in the order of the ``accept:`` block) that
fails, or what to add where it is undecided. Control twins are null controls, never
candidates. Written into the report folder by :mod:`ligwf.report.verdict_records` and
shown by :mod:`ligwf.report.verdict_text`.

The angle criterion is in degrees: the table's ``angle_error`` is relative to the CG1
angle, so its value, interval and floor are multiplied by the CG1 angle of the group
(the relative error's interval holds the CG1 reference's noise; the scale's own, a few
per cent of the angle, is left out). Frame-metric criteria (rigid-block share,
flowing-layer thickness) compare the CG-n value with the CG1 value by interval
arithmetic on both intervals (a CG1 condition of one run: its value +- z x its
within-run error).
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field

import pandas as pd

from ligwf.analysis.records.conditions import REFERENCE_CG, Condition
from ligwf.report.uncertainty import MAX_SUGGESTED_REPLICAS, replicas_to_decide
from ligwf.scene.accept import AcceptSettings
from ligwf.scene.workflow import CONTROL_KEY

PASS, FAIL, UNDECIDED = "pass", "fail", "undecided"
NOT_ASSESSED, NOT_MEASURED = "not assessed", "not measured"
#: condition states
MEETS, FAILS = "meets the budget", "fails"
#: z of a 95 % interval (a one-run CG1 value +- z x its within-run error)
Z95 = 1.959963984540054

#: how a criterion reads the condition table
ERROR, ANGLE, EXCESS, RELATIVE = "error", "angle", "excess", "relative difference"


@dataclass(frozen=True)
class CriterionSpec:
    """One criterion of the budget: its ``accept:`` field, what it reads and how."""

    name: str           # the AcceptSettings field (its tolerance)
    label: str
    unit: str           # of the value and the budget ("" for a ratio)
    column: str         # the condition-table column it reads
    kind: str           # ERROR | ANGLE (error x CG1 angle) | EXCESS | RELATIVE (to CG1)
    floored: bool = False  # accepted up to max(tolerance, the CG1 noise floor)
    gated: bool = False    # only where the granules beat their control


#: The budget's criteria, in the order "fails first" refers to.
CRITERIA = (
    CriterionSpec("angle_deg", "angle of repose", "deg", "angle_error", ANGLE, floored=True),
    CriterionSpec("profile_error", "velocity profile", "", "profile_error", ERROR,
                  floored=True),
    CriterionSpec("rigid_share", "rigid-block frames", "", "rigid_frame_share", EXCESS),
    CriterionSpec("flowing_layer", "flowing layer", "", "flowing_layer_thickness_mean", RELATIVE),
    CriterionSpec("gsd_error", "GSD", "", "gsd_error_all", ERROR, gated=True),
    CriterionSpec("field_error", "continuum fields", "", "field_error", ERROR, floored=True),
)
ANGLE_COLUMN = "angle_of_repose"


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
    budget_source: str = ""   # "tolerance" | "CG1 noise floor (...)"
    note: str = ""            # what would decide it, or why it is not assessed

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


def _reference_band(row, col: str) -> tuple[float, float, float]:
    """A CG1 value's interval; one run: value +- z x its within-run error."""
    v, lo, hi = _band(row, col)
    if not (math.isfinite(lo) and math.isfinite(hi)):
        se = _f(row, f"{col}_se")
        lo, hi = (v - Z95 * se, v + Z95 * se) if math.isfinite(se) else (v, v)
    return v, lo, hi


def is_control_group(group: str) -> bool:
    """A group of control twins (its swept values hold the control key)."""
    try:
        varied = json.loads(group)
    except (TypeError, ValueError):
        return False
    return isinstance(varied, dict) and CONTROL_KEY in varied


# ------------------------------------------------------------------ deciding one criterion
def _decide(spec: CriterionSpec, value: float, lo: float, hi: float, budget: float,
            cg1_replicas: int, replicas: int) -> tuple[str, str]:
    """(state, note) of an interval against its budget."""
    if not (math.isfinite(lo) and math.isfinite(hi)):
        return UNDECIDED, (f"{replicas} CG-n replica{'s' if replicas != 1 else ''}, no "
                           "interval (add CG-n replicas)")
    if hi <= budget:
        return PASS, ""
    if lo > budget:
        return FAIL, ""
    who = "CG1" if spec.kind in (ERROR, ANGLE) else "CG-n and CG1"
    need = replicas_to_decide(value, lo, hi, budget,
                              cg1_replicas if who == "CG1" else max(replicas, 1))
    if need is None:
        return UNDECIDED, "the value sits on the budget (no number of replicas decides)"
    if need > MAX_SUGGESTED_REPLICAS:
        return UNDECIDED, (f"over {MAX_SUGGESTED_REPLICAS} {who} replicas would be needed "
                           "(the value is near the budget for its spread)")
    return UNDECIDED, f"about {need} {who} replicas would decide"


def _measure(spec: CriterionSpec, row, ref) -> tuple[float, float, float, float, str]:
    """(value, lo, hi, floor, floor source) of a criterion in its own unit."""
    if spec.kind in (ERROR, ANGLE):
        value, lo, hi = _band(row, spec.column)
        floor, source = _f(row, f"{spec.column}_floor"), str(row.get(f"{spec.column}_floor_source", ""))
        if spec.kind == ANGLE:
            scale = abs(_f(ref, ANGLE_COLUMN))
            value, lo, hi, floor = (x * scale for x in (value, lo, hi, floor))
        return value, lo, hi, floor, source
    x, x_lo, x_hi = _band(row, spec.column)
    r, r_lo, r_hi = _reference_band(ref, spec.column)
    if spec.kind == EXCESS:   # CG-n above CG1, interval arithmetic
        return x - r, x_lo - r_hi, x_hi - r_lo, math.nan, ""
    if not (r > 0 and r_lo > 0):   # relative to a CG1 value that may be 0: undefined
        return math.nan, math.nan, math.nan, math.nan, ""
    d, d_lo, d_hi = x / r - 1.0, x_lo / r_hi - 1.0, x_hi / r_lo - 1.0
    if d_lo <= 0.0 <= d_hi:      # |.| of an interval holding 0
        return abs(d), 0.0, max(-d_lo, d_hi), math.nan, ""
    return abs(d), min(abs(d_lo), abs(d_hi)), max(abs(d_lo), abs(d_hi)), math.nan, ""


def criterion(spec: CriterionSpec, tolerance: float, row, ref, gate: Gate,
              cg1_replicas: int) -> CriterionResult:
    """One criterion of one CG-n condition (``row``) against its group's CG1 row ``ref``."""
    base = dict(name=spec.name, label=spec.label, unit=spec.unit)
    of_ref = {ERROR: None, ANGLE: ANGLE_COLUMN}.get(spec.kind, spec.column)
    if spec.column not in row.index or (of_ref is not None and of_ref not in ref.index):
        return CriterionResult(**base, state=NOT_MEASURED,
                               note=f"not measured: the study has no {spec.column}")
    if spec.gated and gate.passes is not True:
        return CriterionResult(**base, state=NOT_ASSESSED, note=f"not assessed: {gate.reason}")
    value, lo, hi, floor, source = _measure(spec, row, ref)
    if not math.isfinite(value):
        why = (f"the CG1 {spec.label} (or its interval) reaches 0: no relative difference"
               if spec.kind == RELATIVE and math.isfinite(_f(row, spec.column))
               else f"no {spec.column} value for this condition")
        return CriterionResult(**base, state=NOT_MEASURED, note=f"not measured: {why}")
    budget, budget_source = tolerance, "tolerance"
    if spec.floored and math.isfinite(floor) and floor > tolerance:
        budget, budget_source = floor, f"CG1 noise floor ({source})" if source else "CG1 noise floor"
    state, note = _decide(spec, value, lo, hi, budget, cg1_replicas,
                          int(_f(row, "replicas")) if math.isfinite(_f(row, "replicas")) else 1)
    return CriterionResult(**base, state=state, value=value, lo=lo, hi=hi, budget=budget,
                           budget_source=budget_source, note=note)


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
                         f"({band_text(failed.value, failed.lo, failed.hi, failed.unit)} > "
                         f"{_num(failed.budget)})")
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
           gates: dict[str, Gate] | None = None) -> Verdict:
    """The verdict of every sweep group of a condition table (control groups left out)."""
    gates = gates or {}
    groups = []
    if conditions.empty:
        return Verdict((), accept.model_dump(mode="json"))
    for group, sub in conditions.groupby("group", sort=True):
        group = str(group)
        if is_control_group(group):
            continue
        refs = sub[sub["cg"] == REFERENCE_CG]
        if refs.empty:
            groups.append(GroupVerdict(group, (), "No CG1 case in this group: nothing to "
                                                  "compare the CG levels with."))
            continue
        ref = refs.iloc[0]
        cg1_replicas = int(ref["replicas"])
        gate = gates.get(group, Gate(None, "no cohesionless control ran"))
        out = []
        for _, row in sub[sub["cg"] != REFERENCE_CG].sort_values(["cg", "rule"]).iterrows():
            results = tuple(criterion(spec, getattr(accept, spec.name), row, ref, gate,
                                      cg1_replicas)
                            for spec in CRITERIA if getattr(accept, spec.name) is not None)
            out.append(ConditionVerdict(group, float(row["cg"]), str(row["rule"]),
                                        int(row["replicas"]), *_band(row, "speedup_core"),
                                        results))
        sentence, cheapest = group_sentence(out)
        groups.append(GroupVerdict(group, tuple(out), sentence, cheapest))
    return Verdict(tuple(groups), accept.model_dump(mode="json"))
