"""Shares in [0, 1] whose runs all read 0 (the rigid-block share of a flowing drum): a t
interval on run means has no variance to go on there and read "pass, shown within 0 [0, 0]"
(issue 45). An all-zero arm's mean is bounded over its runs instead (the rule of three),
the other arm keeps its t bound, and the test of CG-n - CG1 against +-budget is made of the
two. Pure, like :mod:`ligwf.inference.equivalence`, whose Estimate and Test it
returns; measured by ``benchmarks/bench_coverage.py --designs`` (all-zero arms).
"""

from __future__ import annotations

import math

import numpy as np
from scipy import optimize, stats

from ligwf.inference.equivalence import (ALPHA, FAIL, PASS, UNDECIDED, Estimate,
                                                Test, finite_values)


def zero_arm_bound(runs: int, alpha: float = ALPHA) -> float:
    """The one-sided (1 - alpha) upper bound of the mean of a share in [0, 1] whose ``runs``
    runs all read 0: 1 - alpha^(1 / R), the rule of three over runs (3 / R at alpha 0.05).
    A run is the unit: its frames are correlated and its seed may or may not make a rigid
    block at all (the 80-min ladder's 31st cg3-weber run read 0.05 after 30 zeros), so
    frames cannot narrow it. Exact for the worst case, a share that is 0 or 1 per run."""
    return 1.0 - alpha ** (1.0 / runs) if runs > 0 else math.nan


def share_bounds(runs, alpha: float = ALPHA) -> tuple[float, float]:
    """One-sided (1 - alpha) lower and upper bounds of the mean of a share in [0, 1] from
    its runs, whatever its distribution: Clopper-Pearson's binomial bounds at the runs' sum
    S of R runs (beta quantiles at S, R - S + 1 and S + 1, R - S). Among shares in [0, 1]
    of a given mean, 0-or-1 runs (binomial) have the heaviest tails (Hoeffding 1956), so
    the bounds hold for shares that are 0 in most runs, where a t bound on the mean does
    not (the benchmark's 60-vs-60 all-zero cell passed wrongly in 0.0685 with one)."""
    x = finite_values(runs)
    n, total = len(x), float(np.sum(np.clip(x, 0.0, 1.0)))
    if n == 0:
        return math.nan, math.nan
    lo = 0.0 if total <= 0 else float(stats.beta.ppf(alpha, total, n - total + 1.0))
    hi = 1.0 if total >= n else float(stats.beta.ppf(1.0 - alpha, total + 1.0, n - total))
    return lo, hi


def share_test(runs, reference, budget: float, alpha: float = ALPHA
               ) -> tuple[Estimate, Test] | None:
    """The difference of a share in [0, 1] (CG-n - CG1) when an arm's runs all read 0,
    where a t interval has no variance to go on ("pass, shown within 0 [0, 0]"); None when
    no arm is all zero (then :func:`difference_estimate` and :func:`equivalence` decide).

    An all-zero arm's mean lies in [0, :func:`zero_arm_bound`]; the other arm's in its
    binomial bounds (:func:`share_bounds`). Both arms zero: [-U_1, U_n], each side at alpha (the pass test's p-value is
    (1 - budget)^R, the chance that R runs all read 0 when the mean share is the budget).
    One arm zero: each one-sided bound splits alpha between the binomial bound of the
    measured arm and the zero arm's bound (Bonferroni), and the fail test's p-value is the smallest
    alpha at which the interval lies wholly outside +-budget, doubled for the two sides."""
    x, y = finite_values(runs), finite_values(reference)
    if len(x) < 2 or len(y) < 2 or not math.isfinite(budget):
        return None
    zx, zy = bool(np.all(x == 0)), bool(np.all(y == 0))
    if not (zx or zy):
        return None
    if zx and zy:
        ux, uy = zero_arm_bound(len(x), alpha), zero_arm_bound(len(y), alpha)
        p_pass = max((1.0 - budget) ** len(x), (1.0 - budget) ** len(y)) if budget < 1 else 0.0
        state = PASS if max(ux, uy) <= budget else UNDECIDED
        return Estimate(0.0, -uy, ux, math.nan, math.nan), Test(state, p_pass, 1.0)
    measured, zero, sign = (y, x, -1.0) if zx else (x, y, 1.0)

    def bounds(a: float) -> tuple[float, float]:
        """(lo, hi) of CG-n - CG1, each side at ``a``."""
        low = share_bounds(measured, a / 2.0)[0]
        high = share_bounds(measured, a)[1]
        u = zero_arm_bound(len(zero), a / 2.0)
        if sign > 0:     # CG-n measured, CG1 zero: delta in [lo_n - U_1, hi_n]
            return low - u, high
        return -high, u - low               # CG1 measured, CG-n zero

    lo, hi = bounds(alpha)
    value = sign * float(measured.mean())

    def p_side(outside) -> float:     # the smallest alpha whose interval lies outside
        if not outside(bounds(0.5)):
            return 1.0
        return float(optimize.brentq(lambda a: 0.5 if outside(bounds(a)) else -0.5,
                                     1e-12, 0.5, xtol=1e-9)) if not outside(
            bounds(1e-12)) else 1e-12

    p_fail = min(1.0, 2.0 * min(p_side(lambda b: b[0] > budget),
                                p_side(lambda b: b[1] < -budget)))
    p_pass = 1.0   # (not used by the family rule; the state comes from the interval)
    state = (PASS if lo >= -budget and hi <= budget else
             FAIL if p_fail <= alpha else UNDECIDED)
    df = float(len(measured) - 1)
    return Estimate(value, lo, hi, math.nan, df), Test(state, p_pass, p_fail)
