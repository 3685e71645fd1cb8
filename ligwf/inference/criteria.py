"""The criteria of the verdict's budget and how one CG-n condition is decided on each
(:mod:`ligwf.report.verdict` combines them into the study's answer).

Signed criteria (angle of repose in deg, rigid-block share, flowing-layer thickness
relative to CG1) are the difference of run means CG-n - CG1 with its (1 - 2 alpha) t
interval (the df rule the caller passes: Welch's for equal arms, Hsu's for unequal ones or
sequential looks), passed by two one-sided tests against +-budget and failed by a two-sided
fail test; a share whose runs all read 0 in an arm is bounded over runs
(:mod:`ligwf.analysis.records.shares`); the velocity profile is the noise-corrected
distance of the mean profiles with noncentral-F bounds; the GSD and field errors keep the
analysis' intervals against the tolerance (the field criterion's at the verdict's alpha,
with the replicas that would decide it from its noise pieces). Holm's step-down over the fail
tests of every tested criterion of a level (each with its own p-value, decided or not)
decides which fails stand. The statistics: :mod:`ligwf.analysis.records.equivalence`.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np
import pandas as pd
from scipy import stats

from ligwf.analysis.records import equivalence as eq
from ligwf.analysis.records import sampling, shares
from ligwf.analysis.records.equivalence import FAIL, PASS, UNDECIDED
from ligwf.analysis.records.field_errors import FIELD_NOISE_COLUMNS, LayerNoise
from ligwf.report import planning
from ligwf.report.deciding import decide_text, field_plan, profile_plan, signed_plan
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
    share: bool = False    # a share in [0, 1] per run: an all-zero arm gets a bound over runs


#: The budget's criteria, in the order "fails first" refers to.
CRITERIA = (
    CriterionSpec("angle_deg", "angle of repose", "deg", "angle_of_repose", SIGNED),
    CriterionSpec("profile_error", "velocity profile", "", "profile_error", PROFILE),
    CriterionSpec("rigid_share", "rigid-block frames", "", "rigid_frame_share", SIGNED,
                  share=True),
    CriterionSpec("flowing_layer", "flowing layer", "", "flowing_layer_thickness_mean", RELATIVE),
    CriterionSpec("gsd_error", "GSD", "", "gsd_error_all", ERROR, gated=True),
    CriterionSpec("field_error", "continuum fields", "", "field_error", ERROR),
)


#: the case-table columns the signed criteria read (their runs' noise costs a decision)
SIGNED_COLUMNS = tuple(s.column for s in CRITERIA if s.kind in (SIGNED, RELATIVE))


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
    #: the cheapest way to decide it (undecided only, :mod:`ligwf.analysis.records.sampling`):
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


def _arm(runs: pd.DataFrame, column: str, noise: pd.DataFrame | None,
         scale: float) -> sampling.Arm:
    """The runs of one arm with their noise and prices (noise table rows by case id)."""
    values = _per_run(runs, column)
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


def _replica_cost(runs: pd.DataFrame, noise: pd.DataFrame | None) -> float:
    """Mean core-seconds of a new replica of an arm (nan without a noise table)."""
    if noise is None or noise.empty or runs is None or planning.REPLICA_COST not in noise:
        return math.nan
    costs = [float(noise[planning.REPLICA_COST].get(i, math.nan)) for i in runs["case_id"]]
    return float(np.nanmean(costs)) if np.isfinite(costs).any() else math.nan


def _signed(spec: CriterionSpec, tolerance: float, x: sampling.Arm, y: sampling.Arm,
            alpha: float, df_rule: str = eq.WELCH) -> tuple[CriterionResult, float]:
    """A signed criterion: the difference of run means CG-n - CG1 (relative to the CG1
    mean for RELATIVE), two one-sided tests at alpha. Returns the result and the p-value
    of its fail test (for Holm over the level)."""
    base = dict(name=spec.name, label=spec.label, unit=spec.unit, budget=tolerance,
                budget_source="tolerance")
    scale = 1.0
    if spec.kind == RELATIVE:
        ref = float(np.nanmean(y.values)) if np.isfinite(y.values).any() else math.nan
        if not ref > 0:
            return CriterionResult(**base, state=NOT_MEASURED, note=(
                f"not measured: the CG1 {spec.label} is 0: no relative difference")), math.nan
        scale = 1.0 / ref
    e = eq.scaled(eq.difference_estimate(x.values, y.values, alpha, df_rule), scale)
    if not math.isfinite(e.value):
        return CriterionResult(**base, state=NOT_MEASURED,
                               note=f"not measured: no {spec.column} value"), math.nan
    zero = shares.share_test(x.values, y.values, tolerance, alpha) if spec.share else None
    if zero is not None:
        return _all_zero(base, spec, zero, x, y, tolerance, alpha)
    test = eq.equivalence(e, tolerance, alpha)
    noise = eq.difference_estimate(x.values, y.values, alpha / 2, df_rule)
    vs_noise = ("" if not noise.has_interval else
                "differs from CG1 beyond seed noise" if (noise.lo > 0 or noise.hi < 0)
                else "indistinguishable from CG1 seed noise at these replicas")
    note, decide = vs_noise, {}
    if test.state == UNDECIDED:
        decide, how = signed_plan(x.scaled(scale), y.scaled(scale), e, tolerance, alpha,
                                     spec.unit, df_rule)
        note = "; ".join(part for part in (how, vs_noise) if part)
    bound = max(abs(e.lo), abs(e.hi)) if e.has_interval else math.nan
    return CriterionResult(**base, state=test.state, value=e.value, lo=e.lo, hi=e.hi,
                           bound=bound, note=note, **decide), test.p_fail


def _all_zero(base: dict, spec: CriterionSpec, zero: tuple[eq.Estimate, eq.Test],
              x: sampling.Arm, y: sampling.Arm, tolerance: float, alpha: float
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


def _holm_replan(r: CriterionResult, x: sampling.Arm, y: sampling.Arm, alpha: float,
                 df_rule: str) -> CriterionResult:
    """What would decide a signed fail that Holm's step-down did not keep: the fail test
    must pass at ``alpha`` (the level's alpha over its family size, which Holm's first step
    asks and which is enough at every later step), so the cheapest option is planned at
    that level, not at the per-test alpha where the fail already holds."""
    scale = 1.0
    if any(c.name == r.name and c.kind == RELATIVE for c in CRITERIA):
        ref = float(np.nanmean(y.values))
        scale = 1.0 / ref if ref > 0 else math.nan
    e = eq.scaled(eq.difference_estimate(x.values, y.values, alpha, df_rule), scale)
    fields, _ = signed_plan(x.scaled(scale), y.scaled(scale), e, r.budget, alpha, r.unit,
                               df_rule)
    return dataclasses.replace(r, **(_NO_DECIDE | fields))


def _norm(spec: CriterionSpec, tolerance: float, x: np.ndarray, y: np.ndarray,
          alpha: float, costs: tuple[float, float] = (math.nan, math.nan)) -> CriterionResult:
    """The velocity profile: the noise-corrected relative L2 distance between the arms'
    mean profiles, decided by its noncentral-F bounds (``costs``: core-seconds of a replica of
    each arm, for what would decide it)."""
    base = dict(name=spec.name, label=spec.label, unit=spec.unit, budget=tolerance,
                budget_source="tolerance")
    e = eq.norm_estimate(x, y, alpha)
    if not math.isfinite(e.value):
        return CriterionResult(**base, state=NOT_MEASURED, note="not measured: no profiles")
    state = eq.norm_decision(e, tolerance)
    decide = {}
    note = f"raw distance {e.raw:.3g} before the noise of both arms is taken off"
    if state == UNDECIDED and e.has_interval:
        decide = profile_plan(x, y, tolerance, alpha, costs)
        r = CriterionResult(**base, state=state, **decide)
        how = decide_text(r) or (f"over {sampling.MOST_REPLICAS} replicas of both arms "
                                 "would be needed")
        note = (f"raw distance {e.raw:.3g}; the bounds [{e.lo:.3g}, {e.hi:.3g}] "
                f"straddle the budget; {how}")
    if not e.has_interval:
        note = "an arm has one run: no variance, no bounds (run at least 2 replicas)"
    return CriterionResult(**base, state=state, value=e.value, lo=e.lo, hi=e.hi, bound=e.hi,
                           note=note, **decide)


def _analysis_interval(spec: CriterionSpec, tolerance: float, row, alpha: float = eq.ALPHA,
                       costs: tuple[float, float] = (math.nan, math.nan)) -> CriterionResult:
    """GSD and field errors: their interval from the analysis against the tolerance (the
    field criterion's at the verdict's alpha, :func:`ligwf.report.fields.add_field_errors`,
    with what would decide it)."""
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
    decide = (field_plan(row, tolerance, alpha, costs)
              if state == UNDECIDED and spec.name == "field_error" else {})
    note = ""
    if state == UNDECIDED:
        how = decide_text(CriterionResult(**base, state=state, **decide))
        note = how or (f"over {sampling.MOST_REPLICAS} replicas of an arm would be needed"
                       if decide else "more replicas of both arms")
    return CriterionResult(**base, state=state, value=value, lo=lo, hi=hi, bound=hi,
                           note=note, **decide)


def condition_criteria(accept: AcceptSettings, row, runs: pd.DataFrame, ref_runs: pd.DataFrame,
                       profiles: dict, gate: Gate, alpha: float = eq.ALPHA,
                       noise: pd.DataFrame | None = None, df_rule: str = eq.WELCH
                       ) -> tuple[CriterionResult, ...]:
    """Every criterion of the budget for one CG-n condition (``row`` of the condition table,
    ``runs`` its cases, ``ref_runs`` its group's CG1 cases), with Holm's step-down over the
    fail tests of every criterion tested (an interval or bounds): a criterion fails only if
    its fail test survives Holm."""
    out, p_fail = [], []
    arms: dict[int, tuple[sampling.Arm, sampling.Arm]] = {}   # signed criteria: their arms
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
            x, y = _arm(runs, spec.column, noise, 1.0), _arm(ref_runs, spec.column, noise, 1.0)
            r, p = _signed(spec, tol, x, y, alpha, df_rule)
            out.append(r)
            p_fail.append(p)
            arms[len(out) - 1] = (x, y)
        elif spec.kind == PROFILE:
            x = [profiles.get(c) for c in runs["case_id"]] if runs is not None else []
            y = [profiles.get(c) for c in ref_runs["case_id"]] if ref_runs is not None else []
            try:
                xa = np.array([p for p in x if p is not None and len(p)], dtype=float)
                ya = np.array([p for p in y if p is not None and len(p)], dtype=float)
            except ValueError:
                xa = ya = np.array([])
            costs = (_replica_cost(runs, noise), _replica_cost(ref_runs, noise))
            out.append(_norm(spec, tol, xa, ya, alpha, costs))
            # its own fail test's p-value, decided or not: the family is every tested
            # criterion, so its size does not depend on the outcome
            p_fail.append(eq.norm_fail_p(xa, ya, tol) if out[-1].assessed
                          and math.isfinite(out[-1].lo) else math.nan)
        elif spec.column not in row.index:
            out.append(CriterionResult(**base, state=NOT_MEASURED,
                                       note=f"not measured: the study has no {spec.column}"))
            p_fail.append(math.nan)
        else:
            costs = (_replica_cost(runs, noise), _replica_cost(ref_runs, noise))
            out.append(_analysis_interval(spec, tol, row, alpha, costs))
            p_fail.append(error_fail_p(spec, tol, row, out[-1]))
    rejected = eq.holm_rejects(p_fail, alpha)
    family = sum(math.isfinite(p) for p in p_fail)
    out = [_holm_replan(r, *arms[i], alpha / family, df_rule)
           if r.state == FAIL and not ok and i in arms else r
           for i, (r, ok) in enumerate(zip(out, rejected))]
    return tuple(_after_holm(r, ok, family) for r, ok in zip(out, rejected))


def error_fail_p(spec: CriterionSpec, tolerance: float, row, r: CriterionResult) -> float:
    """The fail test's p-value of an analysis error (nan: not tested). The field criterion
    from its noise pieces (:meth:`LayerNoise.fail_p`, the test its bounds make); the GSD
    error from its 95 % bootstrap interval read as a normal one (se = width / 2 z_0.975),
    an approximation: the bootstrap gives no p-value."""
    if not (r.assessed and math.isfinite(r.lo) and math.isfinite(r.hi)):
        return math.nan
    if spec.name == "field_error":
        values = [row_value(row, c) for c in FIELD_NOISE_COLUMNS]
        if all(math.isfinite(v) for v in values):
            return LayerNoise(values[0], values[1], values[2], int(values[3]),
                              int(values[4])).fail_p(tolerance)
    se = (r.hi - r.lo) / (2.0 * 1.959963984540054)
    if not se > 0:
        return 0.0 if r.value > tolerance else 1.0
    return float(stats.norm.sf((r.value - tolerance) / se))


_NO_DECIDE = dict(decide_by="", decide_arm="", decide_amount=math.nan, decide_amount_cg1=math.nan,
                  decide_core_hours=math.nan, decide_half_width=math.nan, round_by="",
                  round_arm="", round_amount=math.nan, round_amount_cg1=math.nan,
                  round_core_hours=math.nan)


def _after_holm(r: CriterionResult, rejected: bool, family: int) -> CriterionResult:
    """A fail that Holm's step-down does not keep becomes undecided (saying what would
    decide it); a decided criterion carries no decide option."""
    if r.state == FAIL and not rejected:
        note = "; ".join(p for p in (f"outside the budget on its own, not after Holm over "
                                     f"the level's {family} tested criteria", decide_text(r),
                                     r.note) if p)
        return dataclasses.replace(r, state=UNDECIDED, note=note)
    if r.state in (PASS, FAIL):
        return dataclasses.replace(r, **_NO_DECIDE)
    return r
