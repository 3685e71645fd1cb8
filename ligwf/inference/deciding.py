"""What would decide an undecided criterion of the verdict, and what a sequential round
does instead (:func:`ligwf.inference.verdict.condition_criteria` decides; this module plans).

Two plans per undecided criterion, both from the variance components as measured
(:mod:`ligwf.inference.sampling`): the cheapest way to **decide** it (longer
production or more replicas of an arm, the difference as measured: what the report tells
a user) and the cheapest way to **halve** its half-width (what a round of ``ligwf study
--until-decided`` does: it depends on the variances only, so it does not bias the next
look's test). Signed criteria plan on the arms' run values, the velocity profile on its
noncentral-F bounds with the same number more of both arms, the field criterion on its
noise pieces (:class:`~ligwf.inference.field_errors.LayerNoise`) with more CG-n
replicas, more CG1 replicas or both.
"""

from __future__ import annotations

import math

import numpy as np

from ligwf.analysis.records import steady_window as steady
from ligwf.inference import equivalence as eq
from ligwf.inference import sampling
from ligwf.inference.equivalence import UNDECIDED
from ligwf.inference.field_errors import FIELD_NOISE_COLUMNS, LayerNoise
from ligwf.inference import planning


def round_fields(o: "sampling.Option | None") -> dict:
    """A sequential round's option (see :attr:`CriterionResult.round_by`) as fields."""
    if o is None:
        return {}
    return dict(round_by=o.kind, round_arm=o.arm, round_amount=o.amount,
                round_amount_cg1=o.amount_cg1 if o.kind == sampling.REPLICAS else math.nan,
                round_core_hours=o.core_hours)


def signed_plan(x: sampling.ArmRuns, y: sampling.ArmRuns, e: eq.Estimate, budget: float,
                alpha: float, unit: str, df_rule: str = eq.WELCH) -> tuple[dict, str]:
    """What would decide an undecided signed criterion: the cheapest option's fields and
    its sentence (the arms' variances and the difference as measured)."""
    if x.n < 2 or y.n < 2:
        who = "CG-n" if x.n < 2 else "CG1"
        return {}, f"{who} has one run: no variance, no interval (run at least 2 replicas)"
    best = sampling.cheapest(x, y, e.value, budget, alpha, df_rule)
    fields = round_fields(sampling.cheapest(x, y, budget + 0.5 * (e.hi - e.lo) / 2, budget,
                                             alpha, df_rule)) if e.has_interval else {}
    cg1_replicas = cg1_replicas_text(x, y, e.value, budget, alpha, unit, df_rule)
    if best is None:
        return fields, "; ".join(p for p in (
            f"the difference sits near the budget for its spread: neither "
            f"{sampling.MOST_REPLICAS} replicas of an arm nor "
            f"{sampling.MOST_EXTENSION:g}x longer runs would decide it", cg1_replicas) if p)
    fields |= dict(decide_by=best.kind, decide_arm=best.arm, decide_amount=best.amount,
                  decide_amount_cg1=(best.amount_cg1 if best.kind == sampling.REPLICAS
                                     else math.nan),
                  decide_core_hours=best.core_hours,
                  decide_half_width=best.predicted_half_width)
    return fields, "; ".join(p for p in (
        f"cheapest to decide: {best.text(unit)}; the {sampling.dominant_arm(x, y)} scatter "
        "dominates the width now", cg1_replicas) if p)


def cg1_replicas_text(x: sampling.ArmRuns, y: sampling.ArmRuns, difference: float,
                      budget: float, alpha: float, unit: str, df_rule: str = eq.WELCH) -> str:
    """When the CG1 replicas bound the degrees of freedom, say so (the note's words, "CG1
    seeds", are kept as records hold them): CG1 is the smaller arm (Hsu's
    df are its runs - 1, and Welch's fall towards that as CG-n runs are added) and even the
    most CG-n replicas the planner tries would leave the half-width above the distance of
    the difference from the budget. Empty otherwise."""
    gap = abs(abs(difference) - budget)
    if not (2 <= y.n < x.n) or not gap > 0:
        return ""
    most = sampling.MOST_REPLICAS - x.n
    limit = sampling.half_width(x, y, alpha, add=(most, 0), df_rule=df_rule)
    if not limit >= gap:
        return ""
    df = eq.degrees_of_freedom(x.variance, x.n, y.variance, y.n, df_rule)
    u = f" {unit}" if unit else ""
    return (f"CG1 seeds bound the degrees of freedom (df {df:.3g} with {y.n} CG1 runs against "
            f"{x.n} CG-n; more CG-n runs take it towards {y.n - 1}): even "
            f"{sampling.MOST_REPLICAS} CG-n runs would leave the half-width at {limit:.3g}{u}, "
            f"above the {gap:.3g}{u} a decision needs; more CG1 seeds decide it")


def profile_plan(x: np.ndarray, y: np.ndarray, tolerance: float, alpha: float,
                      costs: tuple[float, float]) -> dict:
    """The fewest replicas added to each arm (the same number, the profile's noise is both
    arms') whose predicted bounds would decide the profile criterion."""
    out: dict = {}
    width = eq.norm_estimate(x, y, alpha, bins=eq.PROFILE_BINS)
    width = width.hi - width.lo
    hours = lambda k: k * (costs[0] + costs[1]) / 3600.0   # noqa: E731
    for k in range(1, sampling.MOST_REPLICAS - max(len(x), len(y)) + 1):
        p = eq.norm_estimate(x, y, alpha, add=(k, k), bins=eq.PROFILE_BINS)
        if not p.has_interval:
            break
        if not out.get("round_by") and p.hi - p.lo <= 0.5 * width:
            out.update(round_by=sampling.REPLICAS, round_arm="CG-n and CG1", round_amount=k,
                       round_amount_cg1=k, round_core_hours=hours(k))
        if eq.norm_decision(p, tolerance) != UNDECIDED:
            out.update(decide_by=sampling.REPLICAS, decide_arm="CG-n and CG1",
                       decide_amount=k, decide_amount_cg1=k, decide_core_hours=hours(k),
                       decide_half_width=0.5 * (p.hi - p.lo))
            break
    return out


def _value(row, col: str) -> float:
    try:
        return float(row.get(col, math.nan))
    except (TypeError, ValueError):
        return math.nan


def field_plan(row, tolerance: float, alpha: float, costs: tuple[float, float]) -> dict:
    """What would decide the field criterion and what halves its bounds' half-width, from
    its noise pieces in the condition table (:class:`LayerNoise`, the distance and the
    per-run scatter as measured): the cheapest of more CG-n replicas, more CG1 replicas or
    the same number more of both (core-hours from ``costs``, a replica of each arm)."""
    values = [_value(row, c) for c in FIELD_NOISE_COLUMNS]
    if not all(math.isfinite(v) for v in values) or min(values[3:]) < 2:
        return {}
    noise = LayerNoise(values[0], values[1], values[2], int(values[3]), int(values[4]))
    half = noise.half_width(alpha)
    options = []       # (core-hours, kind of option, CG-n replicas, CG1 replicas, half-width)
    for arm, step in (("CG-n", (1, 0)), ("CG1", (0, 1)), ("CG-n and CG1", (1, 1))):
        cost = step[0] * costs[0] + step[1] * costs[1]
        if not math.isfinite(cost):
            continue
        halved = decided = None
        for k in range(1, sampling.MOST_REPLICAS + 1):
            h = noise.half_width(alpha, (k * step[0], k * step[1]))
            if halved is None and h <= 0.5 * half:
                halved = k
            if decided is None and (noise.distance + h <= tolerance
                                    or noise.distance - h > tolerance):
                decided = (k, h)
            if halved is not None and decided is not None:
                break
        if halved is not None:
            options.append((halved * cost / 3600.0, "round", arm, halved * step[0],
                            halved * step[1]))
        if decided is not None:
            k, h = decided
            options.append((k * cost / 3600.0, "decide", arm, k * step[0], k * step[1], h))
    out: dict = {}
    rounds = sorted(o for o in options if o[1] == "round")
    if rounds:
        hours, _, arm, kx, ky = rounds[0]
        out.update(round_by=sampling.REPLICAS, round_arm=arm, round_amount=kx,
                   round_amount_cg1=ky, round_core_hours=hours)
    decides = sorted(o for o in options if o[1] == "decide")
    if decides:
        hours, _, arm, kx, ky, h = decides[0]
        out.update(decide_by=sampling.REPLICAS, decide_arm=arm, decide_amount=kx,
                   decide_amount_cg1=ky, decide_core_hours=hours, decide_half_width=h)
    return out


def decide_text(r) -> str:
    """The cheapest way to decide ``r`` (a criterion result) in words (empty when none is
    stored)."""
    if not r.decide_by:
        return ""
    cg1 = r.decide_amount_cg1 if math.isfinite(r.decide_amount_cg1) else 0.0
    return "cheapest to decide: " + sampling.Option(
        r.decide_by, r.decide_arm, r.decide_amount, r.decide_core_hours,
        r.decide_half_width, 0, cg1).text(r.unit)


def too_short_note(runs, ref_runs, noise) -> str:
    """Whether a level's comparison rests on runs too short to show a steady state: the runs
    of either arm (``runs`` CG-n, ``ref_runs`` CG1; case tables) whose steady window starts
    at its cap (the noise table's :data:`~ligwf.inference.planning.AT_CAP`), and the
    production each would need (:data:`~ligwf.inference.planning.LEAST_EXTENSION`, the
    planner's rule). Empty when no run is at its cap or there is no noise table."""
    if noise is None or noise.empty or planning.AT_CAP not in noise:
        return ""
    parts, fixes = [], []
    for name, arm in (("CG-n", runs), ("CG1", ref_runs)):
        ids = [i for i in (arm["case_id"] if arm is not None and "case_id" in arm else [])
               if i in noise.index]
        capped, more = planning.capped_runs(noise, ids)
        if capped:
            parts.append(f"{len(capped)} of {len(ids)} {name} runs")
            fixes.append(f"{more:.3g} s more production on each of those {name} runs")
    if not parts:
        return ""
    return (f"runs too short to show a steady state: the steady window of {' and '.join(parts)} "
            f"starts at its {100 * steady.CAP:.0f} % cap (steady_after: auto found no steady "
            f"start in the first half); what would fix it: {' and '.join(fixes)} (the "
            f"planner's rule: production >= {1 / steady.TARGET_SHARE:g} x the truncation, so "
            f"the window starts by {100 * steady.TARGET_SHARE:.0f} % of it; a capped run's "
            f"truncation taken as {steady.CAPPED_TRUNCATION:g} of its production): 'ligwf study "
            "WORKFLOW --out STUDY --extend-production S' continues every run from its "
            "restarts and analyses again, which tests the start again")
