"""The criteria of the verdict's budget and how one CG-n condition is decided on each
(:mod:`ligwf.report.verdict` combines them into the study's answer).

Signed criteria (angle of repose in deg, rigid-block share, flowing-layer thickness
relative to CG1) are the difference of run means CG-n - CG1 with Welch's interval, decided
by two one-sided tests against +-budget; the velocity profile is the noise-corrected
distance of the mean profiles with bin-wise bounds; the GSD and field errors keep the
analysis' intervals against the tolerance. Holm's step-down over a level's fail tests
decides which fails stand. The statistics: :mod:`ligwf.analysis.records.equivalence`.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np
import pandas as pd

from ligwf.analysis.records import equivalence as eq
from ligwf.analysis.records.equivalence import FAIL, PASS, UNDECIDED
from ligwf.scene.accept import AcceptSettings

#: the states of a criterion beside the tests' own (pass, fail, undecided)
NOT_ASSESSED, NOT_MEASURED = "not assessed", "not measured"

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


# ------------------------------------------------------------------ deciding one criterion
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
    need = eq.arm_replicas_to_decide(x * scale, y * scale, budget, alpha)
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
    if test.state == UNDECIDED:
        note = "; ".join(part for part in (_replica_note(x, y, tolerance, alpha, scale),
                                           vs_noise) if part)
    bound = max(abs(e.lo), abs(e.hi)) if e.has_interval else math.nan
    return CriterionResult(**base, state=test.state, value=e.value, lo=e.lo, hi=e.hi,
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
    state = eq.norm_decision(e, tolerance)
    note = (f"raw distance {e.raw:.3g} before the noise of both arms is taken off"
            if state != UNDECIDED else
            f"raw distance {e.raw:.3g}; the bin-wise bounds [{e.lo:.3g}, {e.hi:.3g}] straddle "
            "the budget: more replicas of both arms narrow them")
    if not e.has_interval:
        note = "an arm has one run: no variance, no bounds (run at least 2 replicas)"
    return CriterionResult(**base, state=state, value=e.value, lo=e.lo, hi=e.hi, bound=e.hi,
                           note=note)


def _analysis_interval(spec: CriterionSpec, tolerance: float, row) -> CriterionResult:
    """GSD and field errors: their interval from the analysis against the tolerance."""
    base = dict(name=spec.name, label=spec.label, unit=spec.unit, budget=tolerance,
                budget_source="tolerance")
    value, lo, hi = band(row, spec.column)
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
            # a fail by its bounds has no p-value: it enters Holm's family as decided
            # (p = 0), which only makes the signed fails beside it harder to keep
            p_fail.append(0.0 if out[-1].state == FAIL else math.nan)
        elif spec.column not in row.index:
            out.append(CriterionResult(**base, state=NOT_MEASURED,
                                       note=f"not measured: the study has no {spec.column}"))
            p_fail.append(math.nan)
        else:
            out.append(_analysis_interval(spec, tol, row))
            p_fail.append(0.0 if out[-1].state == FAIL else math.nan)
    rejected = eq.holm_rejects(p_fail, alpha)
    family = sum(math.isfinite(p) for p in p_fail)
    return tuple(r if r.state != FAIL or ok else dataclasses.replace(
        r, state=UNDECIDED, note=(f"outside the budget on its own, not after Holm over the "
                                  f"level's {family} tested criteria; " + r.note).rstrip("; "))
                 for r, ok in zip(out, rejected))
