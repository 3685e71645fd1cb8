"""The velocity-profile criterion: the noise-corrected relative L2 distance between the
arms' mean profiles, decided by its bounds (:func:`ligwf.inference.equivalence.norm_estimate`
under :data:`~ligwf.inference.equivalence.PROFILE_BINS`: the upper bound from the noncentral
F with the depth bins' correlation counted, the lower bound and the fail test from the F
ratio's null simulated under the runs' own covariance of bins); its fail test's p-value
enters Holm's family whether it decides or not. What would decide it:
:func:`ligwf.inference.deciding.profile_plan` (the same number more replicas of both arms).
"""

from __future__ import annotations

import math

import numpy as np

from ligwf.inference import equivalence as eq
from ligwf.inference import sampling
from ligwf.inference.deciding import decide_text
from ligwf.inference.equivalence import UNDECIDED
from ligwf.inference.planning import REPLICA_COST
from ligwf.inference.registry import (NOT_MEASURED, Criterion, CriterionResult, Decision,
                                      LevelData)


#: the fewest runs of both arms together a profile decision is made on: the bins'
#: correlation is estimated from R1 + R2 - 2 residual degrees of freedom, and at 2 and 2 runs
#: the bounds covered 0.907-0.914 on correlated bins (3 and 3: 0.968-0.979;
#: docs/results/verdict_rates/profiles.txt)
MIN_PROFILE_RUNS = 6


def replica_cost(runs, noise) -> float:
    """Mean core-seconds of a new replica of an arm (nan without a noise table)."""
    if noise is None or noise.empty or runs is None or REPLICA_COST not in noise:
        return math.nan
    costs = [float(noise[REPLICA_COST].get(i, math.nan)) for i in runs["case_id"]]
    return float(np.nanmean(costs)) if np.isfinite(costs).any() else math.nan


def arm_profiles(runs, profiles: dict) -> np.ndarray:
    """The runs' velocity profiles as rows (empty when they do not stack)."""
    found = [profiles.get(c) for c in runs["case_id"]] if runs is not None else []
    return np.array([p for p in found if p is not None and len(p)], dtype=float)


def decide_profile(spec: Criterion, tolerance: float, level: LevelData) -> Decision:
    """The profile criterion on one level, with its own fail test's p-value (the family is
    every tested criterion, so its size does not depend on the outcome)."""
    try:
        xa, ya = arm_profiles(level.runs, level.profiles), arm_profiles(level.ref_runs,
                                                                         level.profiles)
    except ValueError:
        xa = ya = np.array([])
    costs = (replica_cost(level.runs, level.noise), replica_cost(level.ref_runs, level.noise))
    r = profile_result(spec, tolerance, xa, ya, level.alpha, costs)
    p = (eq.norm_fail_p(xa, ya, tolerance, eq.PROFILE_BINS)
         if r.assessed and math.isfinite(r.lo) else math.nan)
    return Decision(r, p)


def profile_result(spec: Criterion, tolerance: float, x: np.ndarray, y: np.ndarray,
                   alpha: float, costs: tuple[float, float] = (math.nan, math.nan)
                   ) -> CriterionResult:
    """The noise-corrected distance and its bounds against the tolerance (``costs``:
    core-seconds of a replica of each arm, for what would decide it)."""
    base = spec.base(tolerance)
    e = eq.norm_estimate(x, y, alpha, bins=eq.PROFILE_BINS)
    if not math.isfinite(e.value):
        return CriterionResult(**base, state=NOT_MEASURED, note="not measured: no profiles")
    state = eq.norm_decision(e, tolerance)
    decide = {}
    note = f"raw distance {e.raw:.3g} before the noise of both arms is taken off"
    too_few = e.has_interval and len(x) + len(y) < MIN_PROFILE_RUNS
    if too_few:
        # too few runs to count the bins' correlation: the bounds are shown, not decided on
        state = UNDECIDED
    if state == UNDECIDED and e.has_interval and spec.plan is not None:
        decide = spec.plan(x, y, tolerance, alpha, costs)
        r = CriterionResult(**base, state=state, **decide)
        how = decide_text(r) or (f"over {sampling.MOST_REPLICAS} replicas of both arms "
                                 "would be needed")
        why = (f"{len(x)} and {len(y)} runs: a profile is decided on at least "
               f"{MIN_PROFILE_RUNS} runs of both arms together (at 2 and 2 its bounds "
               "covered 0.91 on correlated bins: docs/results/verdict_rates, profiles.txt)"
               if too_few else "straddle the budget")
        note = (f"raw distance {e.raw:.3g}; the bounds [{e.lo:.3g}, {e.hi:.3g}]"
                f"{'; ' if too_few else ' '}{why}; {how}")
    if not e.has_interval:
        note = "an arm has one run: no variance, no bounds (run at least 2 replicas)"
    return CriterionResult(**base, state=state, value=e.value, lo=e.lo, hi=e.hi, bound=e.hi,
                           note=note, **decide)
